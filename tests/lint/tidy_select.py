#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Which translation units tests/lint/clang_tidy.sh lints (docs/testing.md, "Lint").

select: prints one line per project translation unit to lint, "<file>\\t<cache key>":
  - every unit (--full; or when the record of the last lint-clean commit, tests/lint/clang_tidy.clean,
    is missing, names a commit this clone does not have, or a .clang-tidy changed since it);
  - else the units that changed since that commit, or include (directly or not, per the build's
    `ninja -t deps`) a project file that changed; a unit without dependency information counts as
    changed. Uncommitted and untracked changes count;
  - less, unless --full, the units whose cache key is in <build>/lint/clang_tidy.cache: the key
    hashes the unit, every project file it includes, every .clang-tidy, its compile command and the
    clang-tidy version, so a unit linted clean before is not linted again until one of them changes.
record <keys file>: adds the keys of units linted clean to the cache.
"""
import argparse
import hashlib
import json
import os
import re
import shlex
import subprocess
import sys

STAMP = "tests/lint/clang_tidy.clean"


def git(source, *args):
    result = subprocess.run(["git", "-C", source, *args], capture_output=True, text=True)
    return result.stdout if result.returncode == 0 else None


def recorded_clean_commit(source):
    """The commit tests/lint/clang_tidy.clean names, if this clone has it."""
    try:
        with open(os.path.join(source, STAMP), encoding="utf-8") as stamp:
            lines = [line.strip() for line in stamp if line.strip() and not line.startswith("#")]
    except OSError:
        return None
    if not lines or git(source, "cat-file", "-e", lines[0] + "^{commit}") is None:
        return None
    return lines[0]


def changed_since(source, commit):
    """Absolute paths changed between `commit` and the working tree (untracked files included)."""
    diff = git(source, "diff", "--name-only", commit)
    untracked = git(source, "ls-files", "--others", "--exclude-standard")
    if diff is None or untracked is None:
        return None
    return {os.path.normpath(os.path.join(source, path)) for path in (diff + untracked).split()}


def dependencies(build, source):
    """Object file -> the project files (source tree, not build tree) it was compiled from."""
    text = subprocess.run(["ninja", "-C", build, "-t", "deps"], capture_output=True, text=True).stdout
    deps, current = {}, None
    for line in text.splitlines():
        if line and not line.startswith(" "):
            current = line.split(":", 1)[0] if "(VALID)" in line else None
            if current is not None:
                deps[current] = set()
        elif current is not None and line.strip():
            path = os.path.normpath(os.path.join(build, line.strip()))
            if path.startswith(source + os.sep) and not path.startswith(build + os.sep):
                deps[current].add(path)
    return deps


def units(build, source, only):
    """(file, object, command) of every project translation unit in compile_commands.json."""
    with open(os.path.join(build, "compile_commands.json"), encoding="utf-8") as database:
        entries = json.load(database)
    found = {}
    for entry in entries:
        path = os.path.normpath(os.path.join(entry["directory"], entry["file"]))
        if not path.startswith(source + os.sep) or path.startswith(build + os.sep):
            continue
        if not re.search(only, path):
            continue
        words = shlex.split(entry.get("command") or " ".join(entry.get("arguments", [])))
        obj = words[words.index("-o") + 1] if "-o" in words else ""
        found[path] = (obj, entry.get("command", ""))
    return found


class Hasher:
    def __init__(self):
        self.memo = {}

    def file(self, path):
        if path not in self.memo:
            try:
                with open(path, "rb") as f:
                    self.memo[path] = hashlib.sha256(f.read()).hexdigest()
            except OSError:
                self.memo[path] = "missing"
        return self.memo[path]


def config_files(source):
    listed = git(source, "ls-files", "--cached", "--others", "--exclude-standard", "*.clang-tidy")
    if listed is None:
        return [os.path.join(source, ".clang-tidy"), os.path.join(source, "tests", ".clang-tidy")]
    return sorted(os.path.join(source, path) for path in listed.split())


def select(args):
    build, source = os.path.realpath(args.build), os.path.realpath(args.source)
    found = units(build, source, args.only)
    if not found:
        sys.exit(f"no project sources in {build}/compile_commands.json")
    deps = dependencies(build, source)
    hasher = Hasher()
    configs = "".join(path + hasher.file(path) for path in config_files(source))
    commit = None if args.full else recorded_clean_commit(source)
    changed = changed_since(source, commit) if commit else None
    if changed is not None and any(os.path.basename(path) == ".clang-tidy" for path in changed):
        changed = None  # new rules: every unit
    cache_file = os.path.join(build, "lint", "clang_tidy.cache")
    cached = set()
    if not args.full and os.path.exists(cache_file):
        with open(cache_file, encoding="utf-8") as cache:
            cached = {line.strip() for line in cache}
    reason = "--full" if args.full else (f"changed since {commit[:12]}" if changed is not None else
                                          f"no usable lint-clean commit in {STAMP}, or a .clang-tidy changed")
    chosen = []
    for path, (obj, command) in sorted(found.items()):
        unit_deps = deps.get(obj)
        if changed is not None and unit_deps is not None and path not in changed and not (unit_deps & changed):
            continue
        key_text = args.tidy_version + configs + command + path + hasher.file(path)
        key_text += "".join(dep + hasher.file(dep) for dep in sorted(unit_deps or ()))
        key = hashlib.sha256(key_text.encode()).hexdigest() if unit_deps is not None else ""
        if key and key in cached:
            continue
        chosen.append(f"{path}\t{key}")
    print(f"{len(chosen)} of {len(found)} units to lint ({reason}; cached clean units skipped)", file=sys.stderr)
    for line in chosen:
        print(line)


def record(args):
    cache_file = os.path.join(os.path.realpath(args.build), "lint", "clang_tidy.cache")
    os.makedirs(os.path.dirname(cache_file), exist_ok=True)
    with open(args.keys, encoding="utf-8") as keys, open(cache_file, "a", encoding="utf-8") as cache:
        for key in keys:
            if key.strip():
                cache.write(key.strip() + "\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mode", choices=["select", "record"])
    parser.add_argument("--build", required=True)
    parser.add_argument("--source", required=True)
    parser.add_argument("--only", default=".")
    parser.add_argument("--full", action="store_true")
    parser.add_argument("--tidy-version", default="")
    parser.add_argument("--keys", help="record: file of keys of units linted clean")
    args = parser.parse_args()
    select(args) if args.mode == "select" else record(args)


if __name__ == "__main__":
    main()
