#!/usr/bin/env bash
# The soak: the simulated, CANopen and bilateral teleoperations under stress-ng while faults are
# injected at random (gateway kill -9 and restart, DDS peers killed mid-call, refused commands,
# random writes to a segment, the CAN drives rebooting), then a report (tools/soak/soak.py).
#   tools/soak.sh [--minutes N (60)] [--seed S] [--interval S (10)] [--out DIR] [--no-stress]
# Builds what is missing first. Exit 1 when anything in the report failed.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
[ -n "${SAW_SOAK_NO_BUILD:-}" ] || tools/build.sh saw-rt saw-gateway saw-can-sim >/dev/null
bin=${SAW_BIN:-$root/build/release/bin}
out=""
args=()
while [ $# -gt 0 ]; do
  case $1 in
    --out) out=$2; shift 2 ;;
    *) args+=("$1"); shift ;;
  esac
done
out=${out:-$root/build/soak-$(date +%Y%m%d-%H%M%S)}
# DDS stays on loopback: the gateways' Fast DDS by default, the soak's Cyclone DDS peers by
# sawdds's default CYCLONEDDS_URI.
exec "$root/.venv/bin/python" tools/soak/soak.py --bin "$bin" --src "$root" --out "$out" "${args[@]}"
