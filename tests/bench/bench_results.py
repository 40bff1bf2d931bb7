# SPDX-License-Identifier: Apache-2.0
"""Benchmark result records and the tables of docs/benchmarks.md (python3 standard library only).

One JSON file per capability in docs/bench-results/ holds that capability's rows: the latest figure
of each benchmark with its goal, command, date, commit and machine. `report` regenerates the tables
between the markers of docs/benchmarks.md (or checks that they are current); `record` writes a new
figure into a row. tests/bench/report.sh and tests/bench/record_result.sh are the entry points; the
format is described in docs/benchmarks.md, "Results format".
"""

import argparse
import datetime
import difflib
import functools
import json
import os
import re
import statistics
import subprocess
import sys
import unicodedata

BEGIN = "<!-- bench-report:begin -->"
END = "<!-- bench-report:end -->"
GOAL_OPS = {"<": "<", "<=": "≤", ">": ">", ">=": "≥", "==": "="}
TOP_FIELDS = {"capability": str, "order": int, "intro": str, "rows": list}
TOP_REQUIRED = ("capability", "order", "rows")
ROW_REQUIRED = ("id", "what", "value", "unit", "command", "date", "commit", "machine", "details")
ROW_OPTIONAL = ("runs", "goal", "extract", "carried_over", "note")
GOAL_FIELDS = ("op", "value", "source")


class RecordError(Exception):
    """A malformed record: the message names the file, the row and the field."""


def fail(path, where, field, message):
    raise RecordError(f"{path}: {where}field '{field}': {message}")


def is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def slug(heading):
    """GitHub's anchor for a Markdown heading."""
    text = heading.strip().lower()
    out = []
    for char in text:
        if char in " -_" or unicodedata.category(char)[0] in "LN" and char not in "`*":
            out.append("-" if char == " " else char)
    return "".join(out)


@functools.lru_cache(maxsize=None)
def anchors(doc_path):
    found = set()
    counts = {}
    in_fence = False
    with open(doc_path, encoding="utf-8") as handle:
        for line in handle:
            if line.startswith("```"):
                in_fence = not in_fence
                continue
            match = None if in_fence else re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
            if match:
                base = slug(match.group(1))
                number = counts.get(base, 0)
                counts[base] = number + 1
                found.add(base if number == 0 else f"{base}-{number}")
    return found


def check_row(path, index, row, ids, docs_dir):
    if not isinstance(row, dict):
        fail(path, f"rows[{index}]: ", "rows", "each row must be an object")
    where = f"rows[{index}] ({row.get('id', '?')}): "
    for field in ROW_REQUIRED:
        if field not in row:
            fail(path, where, field, "missing")
    for field in row:
        if field not in ROW_REQUIRED and field not in ROW_OPTIONAL:
            fail(path, where, field, "unknown field (known: " + ", ".join(ROW_REQUIRED + ROW_OPTIONAL) + ")")
    if not isinstance(row["id"], str) or not re.fullmatch(r"[a-z0-9_]+", row["id"]):
        fail(path, where, "id", f"expected lower-case letters, digits and '_', got {row['id']!r}")
    if row["id"] in ids:
        fail(path, where, "id", f"duplicate id {row['id']!r}")
    ids.add(row["id"])
    if row["value"] is not None and not is_number(row["value"]):
        fail(path, where, "value", f"expected a number or null (not measured yet), got {row['value']!r}")
    for field in ("what", "unit", "command", "details"):
        if not isinstance(row[field], str) or (field != "unit" and not row[field].strip()):
            fail(path, where, field, f"expected a non-empty string, got {row[field]!r}")
    if row["value"] is None:
        for field in ("date", "commit", "machine", "runs", "carried_over"):
            if row.get(field) is not None:
                fail(path, where, field, "must be null or absent while the value is null (not measured yet)")
    else:
        check_measured(path, where, row)
    for field in ("extract", "note"):
        if field in row and (not isinstance(row[field], str) or not row[field].strip()):
            fail(path, where, field, f"expected a non-empty string, got {row[field]!r}")
    if "goal" in row:
        check_goal(path, where, row["goal"])
    check_details(path, where, row["details"], docs_dir)


def check_measured(path, where, row):
    if not isinstance(row["date"], str) or not re.fullmatch(r"\d{4}-\d{2}-\d{2}", row["date"]):
        fail(path, where, "date", f"expected YYYY-MM-DD, got {row['date']!r}")
    try:
        datetime.date.fromisoformat(row["date"])
    except ValueError:
        fail(path, where, "date", f"not a calendar date: {row['date']!r}")
    if not isinstance(row["commit"], str) or not re.fullmatch(r"[0-9a-f]{7,40}", row["commit"]):
        fail(path, where, "commit", f"expected 7-40 hex digits, got {row['commit']!r}")
    if not isinstance(row["machine"], str) or not row["machine"].strip():
        fail(path, where, "machine", f"expected a non-empty string, got {row['machine']!r}")
    if "runs" in row and (not isinstance(row["runs"], list) or not row["runs"]
                          or not all(is_number(v) for v in row["runs"])):
        fail(path, where, "runs", f"expected a non-empty list of numbers, got {row['runs']!r}")
    if "carried_over" in row and (not isinstance(row["carried_over"], str) or not row["carried_over"].strip()):
        fail(path, where, "carried_over", f"expected a non-empty string, got {row['carried_over']!r}")


def check_goal(path, where, goal):
    if not isinstance(goal, dict):
        fail(path, where, "goal", f"expected an object with op, value, source, got {goal!r}")
    for field in goal:
        if field not in GOAL_FIELDS:
            fail(path, where, f"goal.{field}", "unknown field (known: op, value, source)")
    if goal.get("op") not in GOAL_OPS:
        fail(path, where, "goal.op", f"expected one of {', '.join(GOAL_OPS)}, got {goal.get('op')!r}")
    if not is_number(goal.get("value")):
        fail(path, where, "goal.value", f"expected a number, got {goal.get('value')!r}")
    if not isinstance(goal.get("source"), str) or not goal["source"].strip():
        fail(path, where, "goal.source", "expected where the goal comes from (mission, issue N)")


def check_details(path, where, details, docs_dir):
    match = re.fullmatch(r"([A-Za-z0-9_./-]+\.md)(?:#([^\s#]+))?", details)
    if not match:
        fail(path, where, "details", f"expected 'doc.md#anchor' (relative to docs/), got {details!r}")
    doc = os.path.normpath(os.path.join(docs_dir, match.group(1)))
    if not os.path.isfile(doc):
        fail(path, where, "details", f"{match.group(1)} does not exist in {docs_dir}")
    if match.group(2) and match.group(2) not in anchors(doc):
        fail(path, where, "details", f"{match.group(1)} has no heading with anchor #{match.group(2)}")


def load(path, docs_dir):
    try:
        with open(path, encoding="utf-8") as handle:
            data = json.load(handle)
    except json.JSONDecodeError as error:
        raise RecordError(f"{path}: not valid JSON: {error}") from error
    if not isinstance(data, dict):
        raise RecordError(f"{path}: expected a JSON object")
    for field in TOP_REQUIRED:
        if field not in data:
            fail(path, "", field, "missing")
    for field, kind in TOP_FIELDS.items():
        if field in data and (not isinstance(data[field], kind) or isinstance(data[field], bool)):
            fail(path, "", field, f"expected {kind.__name__}, got {data[field]!r}")
    for field in data:
        if field not in TOP_FIELDS:
            fail(path, "", field, "unknown field (known: " + ", ".join(TOP_FIELDS) + ")")
    if not data["rows"]:
        fail(path, "", "rows", "empty")
    ids = set()
    for index, row in enumerate(data["rows"]):
        check_row(path, index, row, ids, docs_dir)
    return data


def load_all(results_dir, docs_dir):
    names = sorted(n for n in os.listdir(results_dir) if n.endswith(".json"))
    if not names:
        raise RecordError(f"{results_dir}: no *.json result files")
    files = [(name, load(os.path.join(results_dir, name), docs_dir)) for name in names]
    orders = {}
    for name, data in files:
        if data["order"] in orders:
            fail(os.path.join(results_dir, name), "", "order",
                 f"{data['order']} is also the order of {orders[data['order']]}")
        orders[data["order"]] = name
    return sorted(files, key=lambda item: item[1]["order"])


def number(value):
    if isinstance(value, int) or (isinstance(value, float) and value.is_integer() and abs(value) < 1e15):
        whole = int(value)
        return f"{whole:,}".replace(",", " ") if abs(whole) >= 10000 else str(whole)
    return f"{value:.6g}"


def with_unit(value, unit):
    text = number(value)
    if not unit:
        return text
    return text + unit if unit in ("%", "×", "°") else f"{text} {unit}"


def goal_met(row):
    goal = row.get("goal")
    if goal is None:
        return "—"
    if row["value"] is None:
        return "pending"
    value, target = row["value"], goal["value"]
    met = {"<": value < target, "<=": value <= target, ">": value > target,
           ">=": value >= target, "==": value == target}[goal["op"]]
    return "met" if met else "**not met**"


def cell(text):
    return text.replace("|", "\\|").replace("\n", " ")


def render_row(row):
    if row["value"] is None:
        figure = "not measured yet"
    else:
        figure = f"**{with_unit(row['value'], row['unit'])}**"
        if "runs" in row and len(row["runs"]) > 1:
            figure += f" ({len(row['runs'])} runs: {number(min(row['runs']))}–{number(max(row['runs']))})"
    if "note" in row:
        figure += f"; {row['note']}"
    goal = row.get("goal")
    goal_text = "—"
    if goal is not None:
        goal_text = f"{GOAL_OPS[goal['op']]} {with_unit(goal['value'], row['unit'])} ({goal['source']})"
    date = "—" if row["date"] is None else row["date"] + ("†" if "carried_over" in row else "")
    commit = "—" if row["commit"] is None else f"`{row['commit'][:10]}`"
    what = f"[{row['what']}]({row['details']})"
    cells = [what, figure, goal_text, goal_met(row), f"`{row['command']}`", date, commit,
             row["machine"] or "—"]
    return "| " + " | ".join(cell(c) for c in cells) + " |"


def render(files):
    lines = [BEGIN, "<!-- Generated by tests/bench/report.sh from docs/bench-results/*.json: edit those, not this. -->",
             ""]
    carried = False
    for name, data in files:
        lines.append(f"### {data['capability']}")
        lines.append("")
        if "intro" in data:
            lines += [data["intro"], ""]
        lines.append(f"Records: [`bench-results/{name}`](bench-results/{name}).")
        lines.append("")
        lines.append("| what | figure | goal | status | command | date | commit | machine, load |")
        lines.append("| --- | --- | --- | --- | --- | --- | --- | --- |")
        for row in data["rows"]:
            lines.append(render_row(row))
            carried = carried or "carried_over" in row
        lines.append("")
    if carried:
        lines.append("† Carried over from the narrative benchmarks.md: the figure, date, command and machine as "
                     "measured then; the commit is the one that recorded the figure unless the record's "
                     "`carried_over` says it is the measured one. A new run replaces the row "
                     "(`tests/bench/record_result.sh`).")
        lines.append("")
    lines.append(END)
    return "\n".join(lines) + "\n"


def splice(doc_text, tables, doc_path):
    start, end = doc_text.find(BEGIN), doc_text.find(END)
    if start < 0 or end < start:
        raise RecordError(f"{doc_path}: markers '{BEGIN}' and '{END}' not found in order")
    return doc_text[:start] + tables + doc_text[end + len(END) + 1:]


def cmd_report(args):
    files = load_all(args.results, os.path.dirname(os.path.abspath(args.doc)))
    with open(args.doc, encoding="utf-8") as handle:
        current = handle.read()
    wanted = splice(current, render(files), args.doc)
    if args.check:
        if wanted != current:
            diff = difflib.unified_diff(current.splitlines(), wanted.splitlines(), args.doc, "generated",
                                        lineterm="")
            print("\n".join(diff))
            print(f"{args.doc}: tables differ from {args.results}/*.json; run tests/bench/report.sh",
                  file=sys.stderr)
            return 1
        print(f"{args.doc}: tables match {len(files)} result files")
        return 0
    if wanted != current:
        with open(args.doc, "w", encoding="utf-8") as handle:
            handle.write(wanted)
        print(f"{args.doc}: tables regenerated from {len(files)} result files")
    else:
        print(f"{args.doc}: already current")
    return 0


def last_json_object(path):
    with open(path, encoding="utf-8") as handle:
        text = handle.read()
    try:
        data = json.loads(text)
        if isinstance(data, dict):
            return data
    except json.JSONDecodeError:
        pass
    for line in reversed(text.splitlines()):
        line = line.strip()
        if line.startswith("{"):
            try:
                return json.loads(line)
            except json.JSONDecodeError:
                continue
    raise RecordError(f"{path}: no JSON object (whole file or one line) found")


def extract(path, field):
    """The number at a dotted path of the file's JSON, optionally scaled: "a.b" or "a.b * 0.001"."""
    field, _, factor = (part.strip() for part in field.partition("*"))
    try:
        scale = float(factor) if factor else 1.0
    except ValueError as error:
        raise RecordError(f"extract '{field} * {factor}': the factor is not a number") from error
    value = last_json_object(path)
    for part in field.split("."):
        if isinstance(value, list) and part.isdigit() and int(part) < len(value):
            value = value[int(part)]
        elif isinstance(value, dict) and part in value:
            value = value[part]
        else:
            raise RecordError(f"{path}: field '{field}' not found (stopped at '{part}')")
    if not is_number(value):
        raise RecordError(f"{path}: field '{field}' is {value!r}, not a number")
    return float(f"{value * scale:.12g}") if factor else value


def machine_now():
    cores = os.cpu_count()
    model = ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as handle:
            model = next((line.split(":", 1)[1].strip() for line in handle if line.startswith("model name")), "")
    except OSError:
        pass
    load = os.getloadavg()[0]
    return f"{cores} cores{', ' + model if model else ''}; load average {load:.1f} when recorded"


def git_commit(root):
    try:
        return subprocess.run(["git", "-C", root, "rev-parse", "--short=10", "HEAD"], check=True,
                              capture_output=True, text=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError) as error:
        raise RecordError(f"{root}: cannot read the commit (git rev-parse): give --commit") from error


def find_row(data, row_id):
    return next((row for row in data["rows"] if row["id"] == row_id), None)


def new_value(args, row):
    if args.from_json:
        field = args.field or (row or {}).get("extract")
        if not field:
            raise RecordError(f"row '{args.row}' has no 'extract' field: give --field")
        runs = [extract(path, field) for path in args.from_json]
    else:
        runs = [float(v) for v in args.value.split(",")]
    return statistics.median(runs), runs


def cmd_record(args):
    path = os.path.join(args.results, args.capability + ".json")
    docs_dir = os.path.dirname(os.path.abspath(args.doc))
    data = load(path, docs_dir)
    row = find_row(data, args.row)
    if row is None:
        missing = [f"--{f}" for f in ("what", "unit", "details", "command") if getattr(args, f) is None]
        if missing:
            raise RecordError(f"{path}: no row '{args.row}'; a new row needs {', '.join(missing)}")
        row = {"id": args.row}
        data["rows"].append(row)
    value, runs = new_value(args, row)
    row["value"] = value
    if len(runs) > 1:
        row["runs"] = runs
    else:
        row.pop("runs", None)
    for field in ("what", "unit", "details", "command", "note"):
        if getattr(args, field) is not None:
            row[field] = getattr(args, field)
    row["date"] = args.date or datetime.datetime.now(datetime.timezone.utc).date().isoformat()
    row["commit"] = args.commit or git_commit(args.root)
    row["machine"] = args.machine or machine_now()
    row.pop("carried_over", None)
    if "note" in row and args.note is None and args.keep_note is False:
        row.pop("note")
    ordered = {key: row[key] for key in ROW_REQUIRED + ROW_OPTIONAL if key in row}
    data["rows"][data["rows"].index(row)] = ordered
    check_row(path, data["rows"].index(ordered), ordered, set(), docs_dir)
    with open(path, "w", encoding="utf-8") as handle:
        json.dump(data, handle, indent=2, ensure_ascii=False)
        handle.write("\n")
    print(f"{path}: {args.row} = {value} {ordered['unit']} ({ordered['date']}, {ordered['commit']})")
    return cmd_report(argparse.Namespace(results=args.results, doc=args.doc, check=False))


def parser(root):
    top = argparse.ArgumentParser(prog="bench_results.py", description=__doc__)
    top.add_argument("--results", default=os.environ.get("PANOPTES_BENCH_RESULTS",
                                                         os.path.join(root, "docs", "bench-results")),
                     help="folder of <capability>.json records (default: docs/bench-results)")
    top.add_argument("--doc", default=os.environ.get("PANOPTES_BENCH_DOC",
                                                     os.path.join(root, "docs", "benchmarks.md")),
                     help="the document whose tables are regenerated (default: docs/benchmarks.md)")
    sub = top.add_subparsers(dest="mode", required=True)
    report = sub.add_parser("report", help="regenerate the tables between the markers")
    report.add_argument("--check", action="store_true", help="only check that they are current (exit 1 if not)")
    record = sub.add_parser("record", help="write a new figure into a row, then regenerate the tables")
    record.add_argument("capability", help="file name in the results folder without .json, e.g. latency")
    record.add_argument("row", help="the row's id, e.g. bodypose_p99")
    source = record.add_mutually_exclusive_group(required=True)
    source.add_argument("--value", help="the figure; several comma-separated runs give their median")
    source.add_argument("--from-json", nargs="+", metavar="FILE",
                        help="benchmark outputs (whole file or last JSON line); one per run, median taken")
    record.add_argument("--field", help="dotted path of the figure in --from-json (default: the row's 'extract')")
    record.add_argument("--command", help="the command that produced it (kept from the row if omitted)")
    record.add_argument("--machine", help="machine and load (default: cores, CPU model, load average now)")
    record.add_argument("--date", help="YYYY-MM-DD (default: today, UTC)")
    record.add_argument("--commit", help="the measured commit (default: git rev-parse HEAD)")
    record.add_argument("--note", help="a short remark shown after the figure")
    record.add_argument("--keep-note", action="store_true", help="keep the row's existing note")
    for field in ("what", "unit", "details"):
        record.add_argument(f"--{field}", help=f"the row's {field} (needed for a new row)")
    return top


def main(argv=None):
    """The command line (argv: the arguments after the program's name; default sys.argv[1:])."""
    root = os.environ.get("PANOPTES_SOURCE_DIR") or os.path.dirname(os.path.dirname(os.path.dirname(
        os.path.abspath(__file__))))
    args = parser(root).parse_args(argv)
    args.root = root
    try:
        return cmd_report(args) if args.mode == "report" else cmd_record(args)
    except RecordError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
