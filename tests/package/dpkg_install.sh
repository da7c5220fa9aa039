#!/usr/bin/env bash
# The .debs installed for real (dpkg -i, maintainer scripts and all) on this machine, the example
# deployments run from /usr, then purged. Changes the system: .ci/run runs it (as root, on a
# machine made for CI); the suite's Package.* tests install into private roots instead.
set -euo pipefail
build=$1
[ "$(id -u)" -eq 0 ] || { echo "dpkg_install.sh: needs root" >&2; exit 1; }
if dpkg-query -W -f='${Status}' sawrt 2>/dev/null | grep -q "ok installed"; then
  echo "dpkg_install.sh: sawrt is installed on this machine already; not touching it" >&2
  exit 1
fi
tmp=$(mktemp -d)
cleanup() { dpkg -P sawrt-dev sawrt >/dev/null 2>&1 || true; rm -rf "$tmp"; }
trap cleanup EXIT
(cd "$build" && cpack -G DEB -B "$tmp/debs" >"$tmp/cpack.log") || { cat "$tmp/cpack.log"; exit 1; }
dpkg -i "$tmp"/debs/sawrt_*.deb "$tmp"/debs/sawrt-dev_*.deb
dpkg -s sawrt sawrt-dev | grep -E '^(Package|Status|Version):'
# The Falcon's udev rule where udev reads it (/lib is /usr/lib on merged-/usr Debian).
rule=/usr/lib/udev/rules.d/70-novint-falcon.rules
[ -e "$rule" ] || { echo "FAIL: $rule is not installed" >&2; exit 1; }
cd "$tmp"
/usr/bin/saw-rt --list-types
/usr/bin/saw-rt /usr/share/sawrt/config/teleop-sim.yaml --stepped --duration 2 --record "$tmp/t.csv" |
  tee "$tmp/out" && grep -q "teleop: ENABLED" "$tmp/out"
cp -r /usr/share/sawrt/examples/lab_component "$tmp/lab"
cmake -S "$tmp/lab" -B "$tmp/lab/build" -G Ninja >/dev/null && cmake --build "$tmp/lab/build" >/dev/null
/usr/bin/saw-rt "$tmp/lab/deployment.yaml" --stepped --duration 2 | tee "$tmp/out" && grep -Eq "spring: 200[0-9] cycles" "$tmp/out"
dpkg -P sawrt-dev sawrt
[ ! -e /usr/bin/saw-rt ] || { echo "FAIL: dpkg -r left /usr/bin/saw-rt" >&2; exit 1; }
[ ! -e "$rule" ] || { echo "FAIL: dpkg -P left $rule" >&2; exit 1; }
echo "ok: dpkg -i, the example deployments from /usr, dpkg -P"
