#!/usr/bin/env bash
# Builds the .deb packages (CPack), installs them with dpkg into a private root (dpkg --root
# --unpack: the packages' files where dpkg puts them, their maintainer scripts — ldconfig — not
# run, dependencies taken from this machine, nothing of the system touched; .ci/run also installs
# them for real with dpkg -i),
# and runs the example deployments from the installed files: the shipped teleop-sim.yaml, and the
# example plug-in built from the installed sources with the installed CMake package.
set -euo pipefail
build=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd "$build" && cpack -G DEB -B "$tmp/debs" >"$tmp/cpack.log") || { cat "$tmp/cpack.log"; exit 1; }
ls "$tmp"/debs/*.deb
root=$tmp/root
mkdir -p "$root/var/lib/dpkg/info" "$root/var/lib/dpkg/updates"
touch "$root/var/lib/dpkg/status"
force=(--force-depends)
[ "$(id -u)" -eq 0 ] || force+=(--force-not-root)
dpkg --root="$root" "${force[@]}" --unpack "$tmp"/debs/sawrt_*.deb "$tmp"/debs/sawrt-dev_*.deb >"$tmp/dpkg.log" 2>&1 ||
  { cat "$tmp/dpkg.log"; exit 1; }
dpkg --root="$root" -l | grep -E '^iU +sawrt(-dev)? '
# The runtime package's Depends come from dpkg-shlibdeps: the system libraries saw-rt uses.
dpkg-deb -f "$tmp"/debs/sawrt_*.deb Depends | grep -q libyaml-cpp ||
  { echo "FAIL: sawrt's Depends lacks the libraries it links" >&2; exit 1; }
for f in usr/bin/saw-rt usr/bin/saw-gateway usr/bin/sawctl usr/lib/systemd/system/saw-rt@.service \
         usr/share/sawrt/config/teleop-sim.yaml usr/include/saw/component.hpp \
         usr/share/sawrt/examples/lab_component/lab_spring.cpp usr/lib/udev/rules.d/70-novint-falcon.rules; do
  [ -e "$root/$f" ] || { echo "FAIL: $f is not installed" >&2; exit 1; }
done
find "$root/usr/lib" -path "*/cmake/sawrt/sawrtConfig.cmake" | grep -q . || { echo "FAIL: no sawrtConfig.cmake" >&2; exit 1; }
# The gateway's mapping modules (the teleoperation's types), and what a lab's own message type
# needs: sawrt's IDL and saw_idl_library.
find "$root/usr/lib" -path "*/sawrt/mappings/libsawrt-teleop.so" | grep -q . ||
  { echo "FAIL: no teleop mapping module in <libdir>/sawrt/mappings" >&2; exit 1; }
for f in usr/share/sawrt/idl/std_msgs/msg/Header.idl usr/share/sawrt/examples/lab_message/lab_msgs_mappings.cpp; do
  [ -e "$root/$f" ] || { echo "FAIL: $f is not installed" >&2; exit 1; }
done
find "$root/usr/lib" -path "*/cmake/sawrt/SawIdl.cmake" | grep -q . || { echo "FAIL: no SawIdl.cmake" >&2; exit 1; }
grep -q "^ExecStart=/usr/bin/saw-rt " "$root/usr/lib/systemd/system/saw-rt@.service" ||
  { echo "FAIL: the unit does not start the installed saw-rt" >&2; exit 1; }

out=$(cd "$tmp" && "$root/usr/bin/saw-rt" "$root/usr/share/sawrt/config/teleop-sim.yaml" --stepped --duration 2 \
  --record "$tmp/teleop.csv")
echo "$out"
grep -Eq '^  teleop: ENABLED, tracking error' <<<"$out" || { echo "FAIL: teleop-sim did not run" >&2; exit 1; }

cp -r "$root/usr/share/sawrt/examples/lab_component" "$tmp/lab"
env -i PATH=/usr/bin:/bin HOME="$tmp" cmake -S "$tmp/lab" -B "$tmp/lab/build" -G Ninja \
  -DCMAKE_PREFIX_PATH="$root/usr" >"$tmp/configure.log" || { cat "$tmp/configure.log"; exit 1; }
env -i PATH=/usr/bin:/bin HOME="$tmp" cmake --build "$tmp/lab/build" >"$tmp/build.log" ||
  { cat "$tmp/build.log"; exit 1; }
out=$(cd "$tmp" && "$root/usr/bin/saw-rt" "$tmp/lab/deployment.yaml" --stepped --duration 2)
echo "$out"
grep -Eq '^  spring: 200[0-9] cycles' <<<"$out" || { echo "FAIL: the example plug-in did not run" >&2; exit 1; }
echo "ok: the .debs install and their example deployments run from the installed files"
