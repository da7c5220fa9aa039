#!/usr/bin/env bash
# The README's main job: installs what is missing, builds, and runs the simulated teleoperation
# deployment (config/teleop-sim.yaml) for 10 s at 1 kHz, then prints its summary.
# Extra arguments go to saw-rt (e.g. --duration 60, --stepped).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
tools/build.sh saw-rt
exec build/release/bin/saw-rt config/teleop-sim.yaml --duration 10 --record build/teleop-sim.csv "$@"
