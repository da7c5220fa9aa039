#!/usr/bin/env bash
# Installs this build into a temporary prefix, builds the example lab component
# (examples/lab_component, as installed) and the example lab law (examples/lab_law) against it
# with nothing but find_package(sawrt), and runs their example deployments — the plug-in beside a
# simulated device, the law on the teleoperation task — under the installed saw-rt.
set -euo pipefail
build=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
for component in runtime dev; do
  cmake --install "$build" --prefix "$prefix" --component "$component" >/dev/null
done
cp -r "$prefix/share/sawrt/examples/lab_component" "$tmp/lab"
# The example sees the installed package only: a clean environment, no path into this tree.
env -i PATH=/usr/bin:/bin HOME="$tmp" cmake -S "$tmp/lab" -B "$tmp/lab/build" -G Ninja \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >"$tmp/configure.log" ||
  { cat "$tmp/configure.log"; exit 1; }
env -i PATH=/usr/bin:/bin HOME="$tmp" cmake --build "$tmp/lab/build" >"$tmp/build.log" ||
  { cat "$tmp/build.log"; exit 1; }

# The installed saw-rt resolves the installed libraries, not the build tree's.
if ldd "$prefix/bin/saw-rt" | grep sawrt_ | grep -v -q "$prefix"; then
  ldd "$prefix/bin/saw-rt"
  echo "FAIL: the installed saw-rt loads sawrt libraries from outside the prefix" >&2
  exit 1
fi
out=$(cd "$tmp" && env -i PATH=/usr/bin:/bin "$prefix/bin/saw-rt" "$tmp/lab/deployment.yaml" --stepped --duration 2)
echo "$out"
grep -Eq '^  spring: 200[0-9] cycles, largest force [1-9]' <<<"$out" ||
  { echo "FAIL: the plug-in's component did not cycle and push (no summary line)" >&2; exit 1; }
grep -Eq '^  device +1\.00ms +200[0-9] ' <<<"$out" ||
  { echo "FAIL: the simulated device did not cycle" >&2; exit 1; }
"$prefix/bin/saw-rt" --plugin "$tmp/lab/build/liblab_spring.so" --list-types | grep -q '^lab_spring .*\[' ||
  { echo "FAIL: --list-types does not show the plug-in's type and origin" >&2; exit 1; }

# The example lab law (examples/lab_law): one file against the installed teleop package, run by
# the installed saw-rt's teleoperation task with `law: lab_coupling`.
cp -r "$prefix/share/sawrt/examples/lab_law" "$tmp/law"
env -i PATH=/usr/bin:/bin HOME="$tmp" cmake -S "$tmp/law" -B "$tmp/law/build" -G Ninja \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >"$tmp/configure.log" ||
  { cat "$tmp/configure.log"; exit 1; }
env -i PATH=/usr/bin:/bin HOME="$tmp" cmake --build "$tmp/law/build" >"$tmp/build.log" ||
  { cat "$tmp/build.log"; exit 1; }
out=$(cd "$tmp" && env -i PATH=/usr/bin:/bin "$prefix/bin/saw-rt" "$tmp/law/deployment.yaml" --stepped --duration 2)
echo "$out"
grep -Eq '^  teleop: ENABLED, tracking error' <<<"$out" ||
  { echo "FAIL: the plug-in's law did not run on the teleoperation task" >&2; exit 1; }
echo "ok: built against the installed sawrt and ran as a plug-in under the installed saw-rt"
