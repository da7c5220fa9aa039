#!/usr/bin/env bash
# An arm and a gripper on one CAN bus: starts saw-can-sim (the arm's three CiA 402 drives) and,
# through saw-socketcand, python canopen playing the gripper's I/O node (node 10) on the virtual
# bus `canopen-shared`, runs saw-rt on config/canopen-shared-bus.yaml, then stops them. Builds
# what is missing first; needs the tools venv (.venv, python canopen). Extra arguments go to
# saw-rt (default: --duration 10).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
tools/build.sh saw-rt saw-can-sim saw-socketcand
bin=build/release/bin
[ $# -gt 0 ] || set -- --duration 10
[ -x .venv/bin/python ] || { echo "no tools venv (.venv): tools/bootstrap.sh makes it" >&2; exit 1; }
pids=()
trap 'kill "${pids[@]}" 2>/dev/null; wait "${pids[@]}" 2>/dev/null; echo "simulators: build/canopen-shared-*.log"' EXIT
wait_for() {  # file, text, pid
  until grep -q "$2" "$1" 2>/dev/null; do
    kill -0 "$3" 2>/dev/null || { cat "$1"; exit 1; }
    sleep 0.1
  done
}
"$bin/saw-can-sim" --bus virtual:canopen-shared --node 1 --node 2 --node 3 \
  --load-inertia 0.002 --friction 2e-6 --priority 70 > build/canopen-shared-drives.log 2>&1 &
pids+=($!)
wait_for build/canopen-shared-drives.log "drives on" $!
"$bin/saw-socketcand" --bus virtual:canopen-shared --port 0 > build/canopen-shared-socketcand.log 2>&1 &
pids+=($!)
wait_for build/canopen-shared-socketcand.log "listening on" $!
port=$(sed -n 's/.*127\.0\.0\.1:\([0-9]*\)$/\1/p' build/canopen-shared-socketcand.log)
.venv/bin/python tests/canopen/system/python_io_node.py --port "$port" --channel canopen-shared --node 10 \
  > build/canopen-shared-io-node.log 2>&1 &
pids+=($!)
wait_for build/canopen-shared-io-node.log "python_io_node:" $!
"$bin/saw-rt" config/canopen-shared-bus.yaml --record build/canopen-shared-bus.csv "$@"
