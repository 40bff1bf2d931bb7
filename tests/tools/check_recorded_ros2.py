#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The ROS 2 channels of a recording, as Foxglove's decoders read them (tests/mcap/decode_ros2.mjs
REPORT and --dump-dir DUMP), against what panoptes_ros2_probe received live (PROBE JSON Lines):
every named channel has its ROS 2 type as schema, every message decodes, and at least 90 % of the
messages are ones the probe received (by frame number, or by header stamp).

    check_recorded_ros2.py REPORT DUMP PROBE /tf /rigid_bodies /lab1/markers ...
"""
import json
import sys

TYPES = {"tf": "tf2_msgs/msg/TFMessage", "rigid_bodies": "mocap4r2_msgs/msg/RigidBodies",
         "markers": "mocap4r2_msgs/msg/Markers", "pose": "geometry_msgs/msg/PoseStamped",
         "twist": "geometry_msgs/msg/TwistStamped"}


def recorded_key(m):
    """A decoded message's identity: its frame number, else its (first) header stamp."""
    if "frame_number" in m:
        return int(m["frame_number"])
    header = m["header"] if "header" in m else m["transforms"][0]["header"]
    stamp = header["stamp"]  # Foxglove's reader gives builtin_interfaces/Time as {sec, nsec}
    return (int(stamp["sec"]), int(stamp["nsec"] if "nsec" in stamp else stamp["nanosec"]))


def probe_key(s):
    """The same for the probe's JSON (its headers carry sec and nanosec directly)."""
    if "frame_number" in s:
        return int(s["frame_number"])
    header = s["header"] if "header" in s else s["transforms"][0]["header"]
    return (int(header["sec"]), int(header["nanosec"]))


def main(report, dump, probe, topics):
    channels = {c["topic"]: c for c in json.load(open(report))["channels"]}
    received = {}
    for line in open(probe):
        sample = json.loads(line)
        if sample["qos"] == "reliable":
            received.setdefault(sample["topic"], set()).add(probe_key(sample))
    ok = True
    for topic in topics:
        channel = channels.get(topic)
        want = TYPES[topic.rsplit("/", 1)[1]]
        if (channel is None or channel["schema"] != want or channel["errors"]
                or channel["decoded"] != channel["messages"] or channel["messages"] < 100):
            print(f"FAIL: {topic}: {channel} (want schema {want}, >= 100 messages all decoded)")
            ok = False
            continue
        with open(f"{dump}/{topic.replace('/', '_')}.jsonl") as f:
            got = {recorded_key(json.loads(line)) for line in f}
        seen = received.get("rt" + topic, set())
        common = len(got & seen)
        print(f"{topic}: {channel['messages']} messages as {channel['schema']}, {common} of them "
              f"received by the probe too (it received {len(seen)})")
        ok = ok and common >= 0.9 * min(len(got), len(seen)) and common > 0
    return 0 if ok else 1


if __name__ == "__main__":
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]))
