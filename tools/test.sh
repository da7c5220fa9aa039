#!/usr/bin/env bash
# The README's test command: installs what is missing, builds (warnings are errors), runs every test.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
tools/build.sh
ctest --preset release --timeout 300 "$@"
