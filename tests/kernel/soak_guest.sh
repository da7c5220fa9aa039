#!/usr/bin/env bash
# In the PREEMPT_RT guest: the soak (tools/soak) on the faults only a real kernel has, at random
# among the drives' reboots and gateway kills: vcan0 taken down and up under the CANopen arm
# (saw-can-sim's drives on it), and the Falcon unplugged and plugged in again (its USB gadget
# unbound and bound again) under a Falcon → simulated Omni teleoperation. Each must fault saying
# why, and an operator's enable (over DDS, on the guest's loopback) must bring it back; nothing
# unexpected may fault, no row be lost, and every saw-rt stop in order (the soak's report).
# Timing limits loosened as the other guest checks do (tools/soak/deployments.py: loosen).
# Usage: soak_guest.sh SRC SAW_RT [SOAK_MINUTES (1, each deployment)]
set -euo pipefail
src=$1
bin=$(dirname "$2")
minutes=${3:-1}
work=$(mktemp -d)
# shellcheck source=tests/kernel/gadget.sh
source "$src/tests/kernel/gadget.sh"
trap gadget_down EXIT
gadget_up "$work"
ip link show vcan0 > /dev/null || { echo "no vcan0"; exit 1; }
# The soak's logs beside the guest's results (RESULTS/soak.guest.d), where the host can read them.
# One deployment at a time: two emulated CPUs do not carry both with their gateways.
logs=${out:-$work}/soak.guest.d
rc=0
soak() {  # soak NAME DEPLOYMENT KINDS [ARGS...]
  local name=$1 deployment=$2 kinds=$3
  shift 3
  local r=0
  "$src/.venv/bin/python" "$src/tools/soak/soak.py" --bin "$bin" --src "$src" --out "$logs/$name" \
    --minutes "$minutes" --seed "${SAW_SOAK_SEED:-1}" --interval 4 --no-stress --loose-timing \
    --deployments "$deployment" --kinds "$kinds" "$@" || r=$?
  if [ "$r" -ne 0 ]; then
    for f in "$logs/$name"/*.err "$logs/$name"/*.out; do
      echo "--- $f (its last lines but the command watchdog's)"
      grep -v "no servo command" "$f" | tail -n 15
    done
    rc=1
  fi
}
soak can canopen can_bus_down,drive_reboot --can-bus socketcan:vcan0
soak falcon falcon falcon_replug,gateway_kill --falcon-firmware "$work/firmware.bin"
exit "$rc"
