#!/usr/bin/env bash
# The README's test command: installs what is missing, builds (warnings are errors), runs every test.
# Then says which tests did not run and why (tools/ci/check_skips.py, from ctest's junit file):
# a skip looks like a pass in ctest's exit code. With --strict, SAW_STRICT_SKIPS=1 or CI set, a
# skip not on tests/structural-skips.txt (or no test run at all) fails the command; otherwise
# the skips are printed and the exit code is ctest's.
# Usage: tools/test.sh [--strict] [ctest arguments...]   (--output-junit FILE is honoured)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

strict=0
if [ -n "${CI:-}" ] || [ "${SAW_STRICT_SKIPS:-0}" = 1 ]; then strict=1; fi
args=()
junit=""
while (($#)); do
  case $1 in
    --strict) strict=1 ;;
    --output-junit)
      # ctest writes a relative path under the build directory; the checker reads it from here.
      [ $# -ge 2 ] || { echo "tools/test.sh: --output-junit needs a file" >&2; exit 2; }
      junit=$(realpath -m "$2")
      shift
      ;;
    *) args+=("$1") ;;
  esac
  shift
done
junit=${junit:-$root/build/release/junit.xml}

tools/bootstrap.sh --tests  # the build's part, then what the tests run (QEMU, Xvfb, the venv...)
tools/build.sh
rc=0
ctest --preset release --timeout 300 --output-junit "$junit" ${args[@]+"${args[@]}"} || rc=$?
check=(python3 tools/ci/check_skips.py "$junit")
((strict)) && check+=(--strict)
if ! "${check[@]}"; then
  echo "tools/test.sh: tests were skipped that CI must run (above); ctest's own exit code was $rc" >&2
  exit $((rc != 0 ? rc : 1))
fi
exit "$rc"
