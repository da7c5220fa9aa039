#!/usr/bin/env bash
# An arm and a gripper on one CAN bus: starts saw-can-sim (the arm's three CiA 402 drives and
# the gripper's I/O node, node 10) on the virtual CAN bus `canopen-shared`, runs saw-rt on
# config/canopen-shared-bus.yaml, then stops them. Builds what is missing first. Extra arguments
# go to saw-rt (default: --duration 10).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
tools/build.sh saw-rt saw-can-sim
bin=build/release/bin
[ $# -gt 0 ] || set -- --duration 10
"$bin/saw-can-sim" --bus virtual:canopen-shared --node 1 --node 2 --node 3 --io 10 \
  --load-inertia 0.002 --friction 2e-6 --priority 70 > build/canopen-shared-nodes.log 2>&1 &
sim=$!
trap 'kill $sim 2>/dev/null; wait $sim 2>/dev/null; echo "nodes: build/canopen-shared-nodes.log"' EXIT
until grep -q "drives on" build/canopen-shared-nodes.log 2>/dev/null; do
  kill -0 $sim 2>/dev/null || { cat build/canopen-shared-nodes.log; exit 1; }
  sleep 0.1
done
"$bin/saw-rt" config/canopen-shared-bus.yaml --record build/canopen-shared-bus.csv "$@"
