#!/usr/bin/env bash
# The README's main job: installs what is missing, builds, runs the demo deployment.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
tools/bootstrap.sh
cmake --preset release >/dev/null
cmake --build --preset release --target saw-demo
exec build/release/tools/demo/saw-demo "$@"
