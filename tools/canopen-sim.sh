#!/usr/bin/env bash
# Teleoperation of a simulated CANopen arm: starts saw-can-sim (three CiA 402 drives on the
# virtual CAN bus `canopen-sim`), runs saw-rt on config/canopen-sim.yaml, then stops the drives.
# Builds what is missing first. Extra arguments go to saw-rt (default: --duration 10).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
tools/build.sh saw-rt saw-can-sim
bin=build/release/bin
[ $# -gt 0 ] || set -- --duration 10
"$bin/saw-can-sim" --bus virtual:canopen-sim --node 1 --node 2 --node 3 \
  --load-inertia 0.002 --friction 2e-6 --priority 70 > build/canopen-sim-drives.log 2>&1 &
sim=$!
trap 'kill $sim 2>/dev/null; wait $sim 2>/dev/null; echo "drives: build/canopen-sim-drives.log"' EXIT
# saw-rt's start-up waits for the nodes' boot-up messages; give the drives a moment to attach.
until grep -q "drives on" build/canopen-sim-drives.log 2>/dev/null; do
  kill -0 $sim 2>/dev/null || { cat build/canopen-sim-drives.log; exit 1; }
  sleep 0.1
done
"$bin/saw-rt" config/canopen-sim.yaml --record build/canopen-sim.csv "$@"
