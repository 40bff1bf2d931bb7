#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A Cyclone DDS application in a secured studio (issue 32 item 5, docs/security.md "Cyclone DDS"):
# panoptes_cyclone_probe on Cyclone DDS 0.10 with deploy/dds/cyclone_secure.xml and an application
# identity issued with `panoptes-security issue ... --cyclone` authenticates with the estimator and
# the cameras on Fast DDS 2.9 and reads the poses; the same program with an identity issued without
# --cyclone, whose certificate subject sorts after the estimator's, never authenticates with it
# (Cyclone cannot decode the DH public key of the handshake request Fast DDS 2.9.1 sends) and reads
# nothing: the documented limitation. Cyclone refuses documents naming domain 232 (code 137) and
# loads the studio's (0..230); a Panoptes node on domain 231 is refused before it joins.
source "$(dirname "$0")/lib.sh"
LC_COLLATE=C  # subject hashes compare as byte strings
scene="$source_dir/deploy/scenes/clients.yaml"
probe="$bin/panoptes_cyclone_probe"
tool="$source_dir/deploy/security/panoptes-security"
[ -x "$probe" ] || { fail "$probe is missing (tests/interop, needs cyclonedds-dev)"; finish; }
# Cyclone DDS on loopback only (no multicast, unicast discovery to 127.0.0.1), plus the studio's
# security files named by PANOPTES_SECURITY_DIR and PANOPTES_SECURITY_IDENTITY.
cyclone="file://$source_dir/deploy/dds/cyclone_loopback.xml,file://$source_dir/deploy/dds/cyclone_secure.xml"
studio="$work/studio"
export PANOPTES_SECURITY_DIR="$studio"

# subject_key CERT: the SHA-256 (hex) of the certificate's DER subject, computed here with openssl
# alone: the lower one's participant sends the handshake request (the 6th field of the TBSCertificate).
subject_key() {
  local offset header length
  read -r offset header length < <(openssl asn1parse -in "$1" |
    sed -n 's/^ *\([0-9]*\):d=2 *hl=\([0-9]*\) *l= *\([0-9]*\) .*/\1 \2 \3/p' | sed -n 6p)
  openssl x509 -in "$1" -outform DER | tail -c +$((offset + 1)) | head -c $((header + length)) | sha256sum | cut -c1-64
}

# --- the studio ----------------------------------------------------------------------------------
"$tool" init "$studio" >/dev/null
"$tool" issue "$studio" estimator estimator >/dev/null
for camera in c0 c1 c2 c3 c4 c5; do "$tool" issue "$studio" camera "$camera" >/dev/null; done
"$tool" issue "$studio" application robot --cyclone >/dev/null
robot_key=$(subject_key "$studio/identities/robot/cert.pem")
lower=$(for cert in "$studio"/identities/*/cert.pem; do
  key=$(subject_key "$cert")
  [[ "$cert" == */robot/* ]] || [[ "$robot_key" < "$key" ]] || echo "$cert"
done)
[ -z "$lower" ] && [[ "$robot_key" == 0000* ]] &&
  pass "robot (--cyclone) sorts before every identity (subject hash ${robot_key:0:12})" ||
  fail "robot's subject hash ${robot_key:0:12} is not below every other: $lower"
listed=$("$tool" list "$studio")
grep -q "^robot .*  cyclone$" <<<"$listed" && [ "$(grep -c "cyclone$" <<<"$listed")" -eq 1 ] &&
  pass "panoptes-security list marks robot, and only robot, as a Cyclone DDS identity" ||
  fail "panoptes-security list: $listed"
# An identity issued without --cyclone sorts at or above 0001...; the one used here after the estimator's.
estimator_key=$(subject_key "$studio/identities/estimator/cert.pem")
first_key=0001
plain=""
for n in 1 2 3 4 5 6 7 8 9 10; do
  "$tool" issue "$studio" application "app$n" >/dev/null
  key=$(subject_key "$studio/identities/app$n/cert.pem")
  [[ "$key" > "$first_key" ]] || fail "app$n (issued without --cyclone) sorts before $first_key: $key"
  [[ "$key" > "$estimator_key" ]] && { plain="app$n"; break; }
done
[ -n "$plain" ] && pass "$plain sorts after the estimator (${key:0:12} > ${estimator_key:0:12})" ||
  fail "none of app1..app10 sorts after the estimator"
grep -q "<max>230</max>" "$studio/governance.xml" && ! grep -q "<max>23[12]</max>" "$studio"/identities/*/permissions.xml &&
  pass "the governance and permissions cover domains 0..230" || fail "documents with another domain range"

# --- domains: Cyclone refuses 232; a Panoptes node on a domain the studio does not cover stops ----
wide="$work/wide"
cp -r "$studio" "$wide"
sed -i 's#<max>230</max>#<max>232</max>#' "$wide/governance.xml"
openssl smime -sign -text -in "$wide/governance.xml" -out "$wide/governance.p7s" -signer "$wide/permissions_ca.pem" \
  -inkey "$wide/ca/ca.key.pem" || fail "cannot sign the wide governance"
PANOPTES_SECURITY_DIR="$wide" PANOPTES_SECURITY_IDENTITY=robot expect_exit 2 \
  "Cyclone DDS refuses a governance covering domains 0..232" -- "$probe" --bodies head --duration 1 --config "$cyclone"
expect_stderr_contains "Can not parse governance file(code: 137)" "... with Cyclone's reason"
PANOPTES_DOMAIN=231 PANOPTES_SECURITY_IDENTITY=app1 expect_exit 2 "a Panoptes node on domain 231 is refused" -- \
  "$bin/panoptes_track_probe" --out "$work/bad.jsonl" --duration 1
expect_stderr_contains "$studio/governance.p7s: governance: no domain_rule covers DDS domain 231 (it covers 0..230;" \
  "... naming the governance, the domain and the domains it covers"

# --- live: estimator and cameras on Fast DDS, two applications on Cyclone DDS -----------------------
expect_exit 0 "simulate the clients scene" -- "$bin/panoptes_sim" features --scene "$scene" --out-dir "$work/sim"
mkdir -p "$work/robot" "$work/plain"
start=$(date +%s)
epoch=$(((start + 9) * 1000000000))
PANOPTES_SECURITY_IDENTITY=robot "$probe" --bodies head,tool --duration 22 --out-dir "$work/robot" --config "$cyclone" \
  >"$work/robot.json" 2>"$work/robot.log" &
robot=$!
pids+=("$robot")
PANOPTES_SECURITY_IDENTITY="$plain" "$probe" --bodies head,tool --duration 16 --out-dir "$work/plain" \
  --config "$cyclone" >"$work/plain.json" 2>"$work/plain.log" &
plain_pid=$!
pids+=("$plain_pid")
sleep 1
PANOPTES_SECURITY_IDENTITY=estimator "$bin/estimator_node" --calibration "$work/sim/calibration.yaml" \
  --bodies "$work/sim/bodies.yaml" --out-poses "$work/own_poses.jsonl" --duration 20 --status-period 5 \
  >"$work/estimator.log" 2>&1 &
estimator=$!
pids+=("$estimator")
# The cameras a second apart: Fast DDS 2.9 handshakes are fragile when many start at once
# (docs/security.md, "What the secured mode does not prevent").
for camera in c0 c1 c2 c3 c4 c5; do
  sleep 1
  PANOPTES_SECURITY_IDENTITY="$camera" replay_cameras "$epoch" 10 "$camera"
done
timeout 40 tail -s 0.05 --pid="$robot" -f /dev/null
wait "$plain_pid"
plain_rc=$?
wait "$robot"
timeout 30 tail -s 0.05 --pid="$estimator" -f /dev/null
expect_clean_exit "$estimator" "the secured estimator" "$work/estimator.log"
for camera in c0 c1 c2 c3 c4 c5; do
  grep -q "not granted\|refused" "$work/$camera.log" && fail "$camera: $(grep -m1 "not granted\|refused" "$work/$camera.log")"
done

# The application issued with --cyclone reads the poses, as the estimator wrote them.
jq -e . "$work/robot.json" >/dev/null 2>&1 || { fail "robot's summary is not JSON"; tail -20 "$work/robot.log"; finish; }
own=$(grep -c '"body"' "$work/own_poses.jsonl" || true)
decoded=$(jq '.native.bodies.samples' "$work/robot.json")
echo "poses: the estimator wrote $own, robot on Cyclone DDS decoded $decoded"
[ "$own" -gt 100 ] && [ "$decoded" -ge $((own * 90 / 100)) ] &&
  pass "robot (Cyclone DDS, secured) decoded >= 90% of the poses ($decoded of $own)" ||
  { fail "robot decoded $decoded of $own poses"; tail -20 "$work/robot.log"; }
jq -c '[.stamp_ns, .body, .p, .q]' "$work/own_poses.jsonl" | sort >"$work/own.keys"
jq -c '[.stamp_ns, .body, .p, .q]' "$work/robot/native_poses.jsonl" | sort >"$work/robot.keys"
differing=$(comm -13 "$work/own.keys" "$work/robot.keys" | wc -l)
[ -s "$work/robot.keys" ] && [ "$differing" -eq 0 ] &&
  pass "every pose robot decoded equals the estimator's own output" ||
  fail "$differing of robot's poses differ from the estimator's own output"
for body in head tool; do
  count=$(jq ".native.bodies.per_body.$body" "$work/robot.json")
  [ "$count" -gt 0 ] && pass "robot read $body ($count poses)" || fail "robot read no pose of $body"
done

# The application issued without --cyclone: the estimator requests the handshake, Cyclone fails it.
plain_decoded=$(jq '.native.bodies.samples + .native.body_descriptions.samples' "$work/plain.json" 2>/dev/null)
if [ -z "$plain_decoded" ]; then
  # No summary: Cyclone DDS 0.10 sometimes crashes (SIGSEGV, exit 139) after failing the estimator's
  # handshake requests over and over ("Begin handshake reply failed: Failed to convert octet
  # sequence to ASN1 integer"); it read nothing either way (docs/security.md). Anything else fails.
  if [ "$plain_rc" -eq 139 ] && grep -q "Begin handshake reply failed" "$work/plain.log"; then
    pass "$plain (no --cyclone) read nothing: Cyclone failed the handshake and then crashed (exit 139, as it sometimes does)"
  else
    fail "$plain (no --cyclone) wrote no summary: exit $plain_rc; stdout $(head -c 200 "$work/plain.json" | tr '\n' ' ')"
    tail -20 "$work/plain.log"
  fi
else
  [ "$plain_decoded" = 0 ] && pass "$plain (no --cyclone, sorts after the estimator) read nothing" ||
    fail "$plain read $plain_decoded samples: the documented limitation no longer holds (docs/security.md)"
fi
grep -q "Failed to convert octet sequence to ASN1 integer" "$work/plain.log" &&
  pass "... because Cyclone cannot decode the estimator's handshake request (the documented reason)" ||
  { fail "$plain's log lacks Cyclone's handshake error"; tail -5 "$work/plain.log"; }
grep -q "ASN1 integer" "$work/robot.log" && fail "robot's log holds a handshake error: $(grep -m1 "ASN1" "$work/robot.log")"
finish
