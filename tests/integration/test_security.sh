#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# DDS Security across hosts (issue 20, docs/security.md). Network namespaces on a bridge that floods
# every frame to every port (a hub: the intruder sees all traffic): a camera host (4 simulated
# camera_nodes), an estimator host, an application host and an intruder host. A studio made by
# deploy/security/panoptes-security; every legitimate node runs the secure profile
# (deploy/dds/secure.xml) with its own identity. Asserts that the secured system tracks; that an
# intruder without a certificate, with one from another CA, with a revoked one (after the CRL is
# re-issued) receives nothing, and that a packet capture in its namespace holds no readable topic
# or type names; that an intruder with an application certificate reads poses but cannot command a
# camera or publish features, nor with a permissions document signed by another CA; that an
# expired certificate and bad security files stop a program with exit 2 before it joins; that a
# camera certificate is scoped to its own camera id: cam1's identity cannot create a writer for
# cam0, and what it writes as cam0 or cam9 from its own partition is dropped by the estimator
# (counted as id_outside_partition), which never counts cam9.
# Root only; skips (77) otherwise.
set -euo pipefail
# One more attempt, only when every failed check is one that a pair of participants that never
# matched explains (a reader that received nothing, a command or an impostor nobody matched): with
# Debian's Fast DDS 2.9.1 such a pair occurs now and then under load (docs/security.md, "Reliability
# of the handshakes"; CI of stop 57 failed on it once, 0 of 6 loaded runs here before it). Any other
# failed check (tracking, intruders, capture, bad files) fails at once. Both attempts' checks are
# printed.
if [ -z "${PANOPTES_SECURITY_ATTEMPT:-}" ]; then
  rc=0
  PANOPTES_SECURITY_ATTEMPT=1 bash "$0" "$@" || rc=$?
  if [ "$rc" -eq 3 ]; then
    echo "RETRY: every failed check above is an unmatched participant pair (Fast DDS 2.9); a second attempt"
    rc=0
    PANOPTES_SECURITY_ATTEMPT=2 bash "$0" "$@" || rc=$?
  fi
  exit "$rc"
fi
here="$(cd "$(dirname "$0")" && pwd)"
source "$here/lib.sh"
source "$here/netns.sh"
netns_test_start
unmatched=0
# fail_unmatched MESSAGE: a failed check that a participant pair that never matched explains.
fail_unmatched() { fail "$* (a pair that never matched?)"; unmatched=$((unmatched + 1)); }

tool="$source_dir/deploy/security/panoptes-security"
secure="$source_dir/deploy/dds/secure.xml"
lan="$source_dir/deploy/dds/lan.xml"
camera_host=1
estimator_host=2
app_host=3
intruder_host=4
netns_create_lan 4 || { fail "could not create the namespaces"; finish; }
# A hub rather than a switch: frames are flooded to every port, so the intruder's capture sees the
# traffic between the other hosts.
ip -n "$(netns_switch)" link set br0 type bridge ageing_time 0

# --- the studio: CA, governance, identities ------------------------------------------------------
studio="$work/studio"
"$tool" init "$studio" >/dev/null
for camera in cam0 cam1 cam2 cam3; do "$tool" issue "$studio" camera "$camera" >/dev/null; done
"$tool" issue "$studio" estimator estimator >/dev/null
"$tool" issue "$studio" application app >/dev/null
"$tool" issue "$studio" console console >/dev/null
"$tool" issue "$studio" operator ops >/dev/null
"$tool" issue "$studio" application mallory >/dev/null
"$tool" issue "$studio" application stale --expired >/dev/null
"$tool" issue "$studio" application leaver >/dev/null
# The leaver keeps a copy of its files and of the revocation list from before its revocation.
leaver="$work/leaver"
mkdir -p "$leaver/identities"
cp "$studio"/{identity_ca.pem,permissions_ca.pem,governance.p7s,identity_crl.pem} "$leaver/"
cp -r "$studio/identities/leaver" "$leaver/identities/"
"$tool" revoke "$studio" leaver >/dev/null
[ ! -e "$studio/identities/leaver" ] && grep -q "BEGIN X509 CRL" "$studio/identity_crl.pem" &&
  pass "panoptes-security: studio CA, governance and 11 identities; the leaver revoked" ||
  fail "panoptes-security setup"
# Every document the tool writes is well-formed XML (issue 32: a comment held '--', which XML
# forbids; Fast DDS tolerated it, xmllint, Python and Cyclone DDS do not): every protection kind,
# and an identity whose name holds '--'.
for protection in sign payload submessage; do "$tool" init "$work/studio-$protection" --protection "$protection" >/dev/null; done
"$tool" issue "$work/studio-sign" application "a--b" >/dev/null
malformed=$(find "$studio" "$work"/studio-* -name '*.xml' -print0 | xargs -0 python3 -c '
import sys, xml.dom.minidom
for path in sys.argv[1:]:
    try:
        xml.dom.minidom.parse(path)
    except Exception as error:
        print(f"{path}: {error}")')
[ -z "$malformed" ] && pass "every governance and permissions document is well-formed XML" ||
  fail "malformed XML from panoptes-security: $malformed"
# Another studio: its CA signed nothing of ours.
"$tool" init "$work/rogue" >/dev/null
"$tool" issue "$work/rogue" application rogue >/dev/null
# Mallory's own permissions, granting every topic, signed by a CA of her own (her identity is ours).
forged="$work/forged"
mkdir -p "$forged/identities/mallory"
cp "$studio"/{identity_ca.pem,identity_crl.pem} "$forged/"
cp "$work/rogue"/{permissions_ca.pem,governance.p7s} "$forged/"
cp "$studio/identities/mallory"/{cert.pem,key.pem} "$forged/identities/mallory/"
sed -e 's#<topic>[^<]*</topic>#<topic>*</topic>#' \
  -e 's#</allow_rule>#<publish><topics><topic>*</topic></topics></publish></allow_rule>#' \
  "$studio/identities/mallory/permissions.xml" >"$forged/identities/mallory/permissions.xml"
openssl smime -sign -text -in "$forged/identities/mallory/permissions.xml" \
  -out "$forged/identities/mallory/permissions.p7s" -signer "$work/rogue/permissions_ca.pem" \
  -inkey "$work/rogue/ca/ca.key.pem"

# --- bad security files: exit 2 before joining, naming the file ---------------------------------
# refused CODE DESCRIPTION -- COMMAND...: as lib.sh's expect_exit, under this test's ERR trap.
refused() {
  local code="$1" what="$2" rc=0
  shift 3
  if "$@" >"$work/last.out" 2>"$work/last.err"; then rc=0; else rc=$?; fi
  if [ "$rc" -eq "$code" ]; then pass "$what (exit $rc)"; else fail "$what: exit $rc, expected $code"; cat "$work/last.err"; fi
}
# secure_args DIR IDENTITY: the options of a node of the secured system.
secure_args() { echo "--dds-profile $secure --security-dir $1 --security-identity $2"; }
probe_once() { netns_exec "$intruder_host" "$bin/panoptes_track_probe" --out "$work/bad.jsonl" --duration 1 "$@"; }
refused 2 "the secure profile without security options is refused" -- probe_once --dds-profile "$secure"
expect_stderr_contains "requires DDS Security" "... and the error says so"
bad="$work/bad"
cp -r "$studio" "$bad" && rm -rf "$bad/ca"
rm "$bad/identities/app/key.pem"
refused 2 "a missing private key is refused" -- probe_once $(secure_args "$bad" app)
expect_stderr_contains "$bad/identities/app/key.pem: private key: no such file" "... naming the file"
echo "not a certificate" >"$bad/identities/console/cert.pem"
refused 2 "a certificate without PEM is refused" -- probe_once $(secure_args "$bad" console)
expect_stderr_contains "$bad/identities/console/cert.pem: identity certificate: no PEM block" "... naming the file"
sed -i 's#</domain_rule>#</domain_rul>#' "$bad/governance.p7s"
refused 2 "a governance document that does not parse is refused" -- probe_once $(secure_args "$bad" ops)
expect_stderr_contains "$bad/governance.p7s: governance: the XML does not parse" "... naming the file"
cp "$studio/governance.p7s" "$bad/governance.p7s"
cp "$studio/identities/ops/key.pem" "$bad/identities/ops/key.pem.tmp"
cp "$studio/identities/mallory/key.pem" "$bad/identities/ops/key.pem"
refused 2 "a private key that does not match the certificate is refused" -- probe_once $(secure_args "$bad" ops)
expect_stderr_contains "DDS Security refused to create the participant" "... with the files named"
cp "$forged/identities/mallory/permissions.p7s" "$bad/identities/mallory/permissions.p7s"
refused 2 "permissions signed by another CA are refused" -- probe_once $(secure_args "$bad" mallory)
expect_stderr_contains "$bad/identities/mallory/permissions.p7s" "... naming the permissions file"
refused 2 "an expired certificate is refused" -- probe_once $(secure_args "$studio" stale)
expect_stderr_contains "$studio/identities/stale/cert.pem" "... naming the certificate"
refused 2 "camera_node: an identity that does not exist is refused" -- \
  netns_exec "$camera_host" "$bin/camera_node" --source "sim:$source_dir/deploy/scenes/demo.yaml#cam0" \
  --duration 1 --quiet $(secure_args "$studio" nobody)
expect_stderr_contains "$studio/identities/nobody: identity: no such directory" "... naming the directory"

# --- the secured system, and the intruders --------------------------------------------------------
scene="$work/scene.yaml"
sed 's/^duration: .*/duration: 14.0/' "$source_dir/deploy/scenes/demo.yaml" >"$scene"
"$bin/panoptes_sim" calibration --scene "$scene" --out "$work/calibration.yaml" >/dev/null
epoch=$((($(date +%s) + 4) * 1000000000))
netns_spawn "$intruder_host" tcpdump -i eth0 -n -U -w "$work/intruder.pcap" udp >"$work/tcpdump.log" 2>&1 &
pids+=("$!")
netns_spawn "$estimator_host" "$bin/estimator_node" --calibration "$work/calibration.yaml" \
  $(secure_args "$studio" estimator) --out-tracks "$work/tracks.jsonl" --duration 21 >"$work/estimator.log" 2>&1 &
pids+=("$!")
estimator=$!
# Staggered starts: with Fast DDS 2.9 a node that authenticates while many others do (a loaded
# machine, ten participants at once) now and then never matched one peer's endpoints.
sleep 1
netns_spawn "$app_host" "$bin/panoptes_track_probe" $(secure_args "$studio" app) --out "$work/app.jsonl" \
  --duration 20 >"$work/app.log" 2>&1 &
pids+=("$!")
netns_spawn "$app_host" "$bin/panoptes_track_probe" $(secure_args "$studio" console) --status \
  --out "$work/console.jsonl" --duration 20 >"$work/console.log" 2>&1 &
pids+=("$!")
sleep 1
for i in 0 1 2 3; do
  netns_spawn "$camera_host" "$bin/camera_node" --source "sim:$scene#cam$i" --sim-epoch-ns "$epoch" \
    $(secure_args "$studio" "cam$i") --quiet >"$work/cam$i.log" 2>&1 &
  pids+=("$!")
done
# The intruders, while the system runs.
intruder_probe() {  # intruder_probe TAG ARGS...: a 10 s track reader on the intruder's host
  local tag="$1"
  shift
  netns_spawn "$intruder_host" "$bin/panoptes_track_probe" --out "$work/$tag.jsonl" --duration 10 "$@" \
    >"$work/$tag.log" 2>&1 &
  pids+=("$!")
}
# Mallory (an application certificate) reads poses from the intruder's host; the operator watches
# the cameras' status (threshold) from the application host and later sets cam3's threshold, from a
# script that waits until every camera has authenticated it and matched its writer. They start
# with the system, so that their handshakes do not compete with the intruders' below, but one
# second after the cameras: in one suite run (issue 37), mallory started in the same instant as the
# four cameras and the two ctl participants and never received a TrackFrame, with no error in any
# log. The likely cause is a handshake given up after its last resend; later Fast DDS versions
# expose max_handshake_requests for this, 2.9.1 has no such setting.
sleep 1
netns_spawn "$intruder_host" "$bin/panoptes_track_probe" --out "$work/mallory.jsonl" --duration 16 \
  $(secure_args "$studio" mallory) >"$work/mallory.log" 2>&1 &
pids+=("$!")
sleep 1
printf 'sleep 4\nwait_nodes 4 6\n* set_threshold 61\n' >"$work/ops_script.txt"
netns_spawn "$app_host" "$bin/panoptes_ctl" script "$work/ops_script.txt" --timeout 10 $(secure_args "$studio" ops) \
  >"$work/ctl_ops.log" 2>&1 &
pids+=("$!")
ops_command=$!
netns_spawn "$app_host" "$bin/panoptes_ctl" status --count 1000 --timeout 14 $(secure_args "$studio" ops) \
  >"$work/status.jsonl" 2>"$work/status.log" &
pids+=("$!")
status_reader=$!
sleep 4
# A tampered program that writes as cam0 and as cam9 from cam1's own partition (cam1's certificate).
# Two of them, one before the intruders' burst and one during it: with Fast DDS 2.9 a pair of
# participants now and then never matches (docs/security.md), and one impostor once matched
# neither the estimator nor the operator's reader (issue 37); two independent participants, started
# apart, make that four unmatched pairs.
impostor() {  # impostor TAG: 5 s of FeatureFrames as cam0 and cam9
  netns_spawn "$intruder_host" env PANOPTES_SECURITY_DIR="$studio" PANOPTES_SECURITY_IDENTITY=cam1 \
    "$bin/panoptes_feature_flood" --dds-profile "$secure" --partition cam1 --camera-ids cam0,cam9 --tracks 0 \
    --rate 100 --duration 5 >"$work/$1.log" 2>&1 &
  pids+=("$!")
}
impostor impostor_a
sleep 1
intruder_probe nocert --dds-profile "$lan"
intruder_probe rogue $(secure_args "$work/rogue" rogue)
intruder_probe leaver $(secure_args "$leaver" leaver)
intruder_probe forged $(secure_args "$forged" mallory)
ctl() { netns_exec "$@"; }
ctl "$intruder_host" "$bin/panoptes_ctl" command cam0 set_threshold 255 --timeout 3 $(secure_args "$studio" mallory) \
  >"$work/ctl_mallory.log" 2>&1 && fail "mallory's application identity sent a camera command" ||
  pass "mallory's application identity may not write camera commands (panoptes_ctl fails)"
grep -q "not granted" "$work/ctl_mallory.log" && pass "... and says the permissions do not grant it" ||
  { fail "ctl error"; cat "$work/ctl_mallory.log"; }
ctl "$intruder_host" "$bin/panoptes_ctl" command cam0 set_threshold 255 --timeout 2 $(secure_args "$forged" mallory) \
  >"$work/ctl_forged.log" 2>&1 || true
# A stolen (or tampered) camera certificate: cam1's identity, from the intruder's host.
netns_exec "$intruder_host" "$bin/camera_node" --source "sim:$scene#cam1" --camera-id cam0 --duration 1 \
  --quiet $(secure_args "$studio" cam1) >"$work/cam1_as_cam0.log" 2>&1 &&
  fail "cam1's certificate started a camera_node publishing as cam0" ||
  { grep -q "not granted" "$work/cam1_as_cam0.log" &&
    pass "cam1's certificate cannot publish as cam0 (camera_node refused: not granted)" ||
    { fail "camera_node as cam0 with cam1's certificate"; tail -n 3 "$work/cam1_as_cam0.log"; }; }
# rt/panoptes/calibration (issue 36): only the estimator role publishes it; a camera's, an operator's
# or an application's certificate may not, so no forged calibration reaches the cameras or consoles.
for identity in cam1 ops mallory; do
  netns_exec "$intruder_host" env PANOPTES_SECURITY_DIR="$studio" PANOPTES_SECURITY_IDENTITY="$identity" \
    "$bin/panoptes_rogue" --dds-profile "$secure" --topics rt/panoptes/calibration --duration 1 \
    >"$work/calibration_$identity.log" 2>&1 &&
    fail "$identity's certificate published on rt/panoptes/calibration" ||
    { grep -q "not granted" "$work/calibration_$identity.log" &&
      pass "$identity's certificate may not publish the calibration (not granted)" ||
      { fail "calibration writer with $identity's certificate"; tail -n 3 "$work/calibration_$identity.log"; }; }
done
# ... and the second tampered program.
impostor impostor_b
# A second reader with mallory's application certificate, started apart from the first: in one
# check run (issue 37, 4756fae run 5) the first never matched the estimator's writer (Fast DDS
# 2.9, docs/security.md); "an application certificate reads poses" holds when either does.
netns_spawn "$intruder_host" "$bin/panoptes_track_probe" --out "$work/mallory2.jsonl" --duration 7 \
  $(secure_args "$studio" mallory) >"$work/mallory2.log" 2>&1 &
pids+=("$!")
netns_spawn "$intruder_host" env PANOPTES_SECURITY_DIR="$forged" PANOPTES_SECURITY_IDENTITY=mallory \
  "$bin/panoptes_feature_flood" --dds-profile "$secure" --cameras 8 --rate 50 --duration 5 \
  >"$work/flood.log" 2>&1 &
pids+=("$!")
# The operator may command: a threshold of 61 on every camera is the positive control.
wait "$ops_command" && pass "the operator's command was sent" || { fail "operator command"; cat "$work/ctl_ops.log"; }
timeout 20 tail -s 0.05 --pid="$status_reader" -f /dev/null || true
timeout 30 tail -s 0.05 --pid="$estimator" -f /dev/null || true
expect_clean_exit "$estimator" estimator_node "$work/estimator.log"
sleep 1
kill -INT "${pids[0]}" 2>/dev/null || true

# --- what each side saw ----------------------------------------------------------------------------
# At most one re-acquisition per marker: on a machine loaded 15 deep (2 cores) one run lost each of
# the 3 markers once; the other runs here (load 9-10) had none.
if "$bin/panoptes_eval" --scene "$scene" --tracks "$work/tracks.jsonl" --epoch-ns "$epoch" \
  --require-rmse-mm 2 --require-tracked 0.95 --require-max-id-switches 3 >"$work/eval.txt" 2>&1; then
  pass "the secured system tracks across hosts (RMSE < 2 mm, >= 95% tracked, <= 3 ID switches)"
  grep -E "^m[0-9]" "$work/eval.txt" || true
else
  # A camera whose clock-sync requests got no reply at all ran on its own clock the whole run: the
  # estimator's time-sync writer and its reader never matched (seen in stop 87's fresh check: cam3,
  # 297 requests, 0 replies, 0 predictions received; worst marker 2.29 mm). Its unsynchronised
  # stamps are what the accuracy check then fails on; the second attempt must pass it.
  unsynced="$(grep -lE 'clock sync: not synchronised \([0-9]+ requests, 0 replies\)' "$work"/cam[0-3].log 2>/dev/null |
    xargs -r -n1 basename | sed 's/\.log$//' | tr '\n' ' ')"
  if [ -n "$unsynced" ]; then
    fail_unmatched "tracking accuracy with DDS Security, with no clock-sync reply ever reaching ${unsynced% }"
  else
    fail "tracking accuracy with DDS Security"
  fi
  cat "$work/eval.txt"; tail -n 3 "$work"/cam*.log "$work/estimator.log"
fi
frames() { grep -c '"type":"tracks"' "$work/$1.jsonl" 2>/dev/null || true; }
[ "$(frames app)" -gt 300 ] && pass "the application host received $(frames app) TrackFrames" ||
  fail_unmatched "the application host received $(frames app) TrackFrames"
{ [ "$(frames mallory)" -gt 100 ] || [ "$(frames mallory2)" -gt 100 ]; } &&
  pass "an application certificate reads poses ($(frames mallory) and $(frames mallory2) TrackFrames)" ||
  fail_unmatched "mallory's application identity received $(frames mallory) and $(frames mallory2) TrackFrames"
# system_frames TAG: TrackFrames from the estimator (they name the camera whose frame produced them);
# forged_frames TAG: those of the intruders' feature flood (no camera).
count_frames() {
  python3 -c "
import json, sys
n = 0
for line in open(sys.argv[1]):
    r = json.loads(line)
    n += r['type'] == 'tracks' and (r['camera'] != '') == (sys.argv[2] == 'system')
print(n)" "$work/$1.jsonl" "$2"
}
for tag in nocert rogue leaver forged; do
  [ -s "$work/$tag.log" ] && grep -q "track frames received" "$work/$tag.log" && [ "$(count_frames "$tag" system)" -eq 0 ] &&
    pass "$tag: the intruder's reader received nothing from the system" ||
    { fail "$tag: the intruder received $(count_frames "$tag" system) TrackFrames, or did not run"; tail -n 3 "$work/$tag.log"; }
done
[ "$(count_frames app forged)" -eq 0 ] && [ "$(count_frames mallory forged)" -eq 0 ] &&
  { [ ! -s "$work/mallory2.jsonl" ] || [ "$(count_frames mallory2 forged)" -eq 0 ]; } &&
  pass "the applications received none of the forged TrackFrames ($(count_frames forged forged) went to the forger's own reader)" ||
  fail "an application received forged TrackFrames"
# The operator's threshold (61): the cameras that applied it (their logs name the command) are those
# its writer matched (the script waits for all four; with Fast DDS 2.9 on a loaded machine a pair
# of participants now and then never matches, docs/security.md), and every one of them whose
# status the operator's reader saw reports 61 (the reader may miss a different camera); the
# intruders' (255) none.
matched=$(sed -n 's/^sent set_threshold to \* (seq [0-9]*, \([0-9]*\) node(s) matched, partition \*)$/\1/p' "$work/ctl_ops.log")
ops_seq=$(sed -n 's/^sent set_threshold to \* (seq \([0-9]*\), .*/\1/p' "$work/ctl_ops.log")
# (|| true: no camera applied it when the operator's command never went out; the checks below say so.)
applied=$(grep -l "command set_threshold #${ops_seq:-none} applied" "$work"/cam[0-9].log 2>/dev/null | sed 's#.*/\(cam[0-9]*\)\.log#\1#' | tr '\n' ' ' || true)
read -r seen checked operator_set intruder_set < <(python3 -c "
import json, sys
last, ever = {}, set()
for line in open(sys.argv[1]):
    if not line.startswith('{'): continue
    s = json.loads(line)
    last[s['camera_id']] = s['threshold']
    if s['threshold'] == 255: ever.add(s['camera_id'])
applied = sys.argv[2].split()
both = [c for c in applied if c in last]
print(len(last), len(both), sum(last[c] == 61 for c in both), len(ever))" "$work/status.jsonl" "$applied")
applied=$(echo $applied)
n_applied=$(echo $applied | wc -w)
[ "${matched:-0}" -ge 2 ] && [ "$n_applied" -eq "${matched:-0}" ] && [ "$checked" -ge 1 ] && [ "$operator_set" -eq "$checked" ] &&
  pass "the operator's threshold (61) was applied by the $n_applied cameras its writer matched ($applied); all $checked of them the operator saw report it" ||
  { fail_unmatched "the operator's command: ${matched:-no} matched, applied by '$applied', $checked of them seen, $operator_set reporting 61"; cat "$work/ctl_ops.log"; }
[ "$intruder_set" -eq 0 ] && pass "no camera ever took the intruders' threshold (255)" ||
  fail "$intruder_set cameras took the intruders' threshold"
# The estimator's per-camera counters: the four real cameras, none of the flood's cam4..cam7.
cameras="$(python3 -c "
import json, sys
names = set()
for line in open(sys.argv[1]):
    r = json.loads(line)
    if r['type'] == 'status': names |= set(r['cameras'])
print(' '.join(sorted(names)))" "$work/console.jsonl")"
case " $cameras " in
  *" cam4 "* | *" cam5 "* | *" cam6 "* | *" cam7 "* | *" cam9 "*) fail "the estimator's per-camera counters name: '$cameras'" ;;
  "  ") fail_unmatched "the console's reader saw no estimator status" ;;
  *) pass "the estimator counted frames from the system's cameras only ($cameras)" ;;
esac
# The impostors (cam1's certificate writing as cam0 and cam9) ran, and the estimator dropped its
# samples as naming another camera than their writer's partition.
outside="$(python3 -c "
import json, sys
n = 0
for line in open(sys.argv[1]):
    r = json.loads(line)
    if r['type'] == 'status': n = max(n, r.get('counters', {}).get('id_outside_partition', 0))
print(n)" "$work/console.jsonl")"
# The operator's status reader got the impostor's CameraStatus too: dropped, never printed. (Either
# reader may be a pair that never matched the impostor, docs/security.md; both rarely are.)
status_dropped=$(sed -n 's/^panoptes_ctl: dropped \([0-9]*\) status messages (id_outside_partition)$/\1/p' "$work/status.log")
grep -q "FeatureFrames in" "$work/impostor_a.log" "$work/impostor_b.log" && [ "$outside" -gt 100 ] ||
  [ "${status_dropped:-0}" -gt 3 ] &&
  pass "cam1's certificate writing as cam0 and cam9 was dropped (id_outside_partition): estimator $outside, operator ${status_dropped:-0}" ||
  { fail_unmatched "impostor: estimator $outside, operator ${status_dropped:-0} samples counted id_outside_partition"; tail -n 3 "$work"/impostor_?.log; }
grep -q '"camera_id":"cam9"' "$work/status.jsonl" && fail "the operator was shown the impostor's cam9" ||
  pass "the operator was never shown a status of the impostor's cam9"
# The intruder's capture: traffic flowed past it, and none of it is readable.
bytes=$(stat -c %s "$work/intruder.pcap" 2>/dev/null || echo 0)
[ "$bytes" -gt 200000 ] && pass "the intruder captured $bytes bytes of the system's traffic" ||
  fail "the intruder's capture holds only $bytes bytes"
# Every RTPS message the other hosts sent is protected (SRTPS_PREFIX first) except the two kinds
# DDS Security sends in clear so that authentication can start: participant announcements (SPDP)
# and the authentication handshake (which carries certificates and permissions documents, not
# samples). A DATA from any other writer in clear would be a readable sample.
read -r protected clear_samples < <(python3 - "$work/intruder.pcap" "$(netns_ip "$intruder_host")" <<'PY'
import socket, struct, sys
data = open(sys.argv[1], "rb").read()
intruder = socket.inet_aton(sys.argv[2])
little = data[:4] == b"\xd4\xc3\xb2\xa1"
endian = "<" if little else ">"
offset, protected, clear = 24, 0, 0
in_clear_ok = {b"\x00\x01\x00\xc2", b"\x00\x02\x01\xc3"}  # SPDP writer, stateless (handshake) writer
while offset + 16 <= len(data):
    _, _, captured, _ = struct.unpack(endian + "IIII", data[offset:offset + 16])
    frame = data[offset + 16:offset + 16 + captured]
    offset += 16 + captured
    if len(frame) < 34 or frame[12:14] != b"\x08\x00" or frame[23] != 17: continue
    ip_len = (frame[14] & 0x0F) * 4
    if frame[26:30] == intruder: continue  # the intruder's own traffic
    rtps = frame[14 + ip_len + 8:]
    if rtps[:4] != b"RTPS": continue
    at = 20
    while at + 4 <= len(rtps):
        kind, flags = rtps[at], rtps[at + 1]
        length = struct.unpack(("<" if flags & 1 else ">") + "H", rtps[at + 2:at + 4])[0]
        if kind == 0x33:  # SRTPS_PREFIX: the rest of the message is protected
            protected += 1
            break
        if kind in (0x15, 0x16) and rtps[at + 12:at + 16] not in in_clear_ok:
            clear += 1
        if length == 0: break
        at += 4 + length
print(protected, clear)
PY
)
[ "$protected" -gt 1000 ] && pass "$protected protected RTPS messages went past the intruder" ||
  fail "only $protected protected RTPS messages in the intruder's capture"
[ "$clear_samples" -eq 0 ] && pass "no sample in clear in the intruder's capture" ||
  fail "$clear_samples samples in clear in the intruder's capture"
leaks=$(grep -a -c "panoptes::msg" "$work/intruder.pcap" || true)
[ "$leaks" -eq 0 ] && pass "no type name (discovery of topics) readable in the capture" ||
  fail "$leaks readable type names in the intruder's capture"

netns_check_isolated && pass "namespaces isolated" || fail "namespace isolation"
netns_cleanup
if [ "$failures" -gt 0 ] && [ "$failures" -eq "$unmatched" ] && [ "$PANOPTES_SECURITY_ATTEMPT" = 1 ]; then
  echo "$failures check(s) failed, each explained by a pair that never matched"
  exit 3
fi
finish
