#!/usr/bin/env bash
# In the PREEMPT_RT guest: saw-rt's Falcon over real USB, against tests/kernel/falcon_gadget.py (a
# Falcon played as a USB gadget on dummy_hcd): the firmware upload, homing and the teleoperation
# of config/teleop-falcon-sim.yaml switched to `transport: usb`; then the gadget is unbound
# mid-run, and the Falcon must FAULT with zero force, saying why. Prints the exchange rate.
# Usage: falcon_usb.sh SRC SAW_RT
set -euo pipefail
src=$1
saw_rt=$2
work=$(mktemp -d)
# shellcheck source=tests/kernel/gadget.sh
source "$src/tests/kernel/gadget.sh"
trap gadget_down EXIT
gadget_up "$work"
# Under software emulation a cycle stalls for tens of ms: the limits on missed exchanges, on a
# transfer's wait, on stale inputs and the tasks' deadline policies are loosened (the USB path is
# under test, not the timing: a starved loop's deadline FAULT is System.AStarvedTeleoperation…'s
# and the CANopen checks'; here it would fault the teleoperation before the Falcon is unplugged).
sed -E -e "s#^( +)transport: sim#\1transport: usb\n\1firmware: $work/firmware.bin\n\1max_missed: 200\n\1usb: {bus: -1, index: 0, exchange_timeout_ms: 20}#" \
  -e "s#stale_timeout: 20ms#stale_timeout: 500ms#" \
  -e "s#task: \{period: 1ms, #task: {period: 1ms, deadline: {in_a_row: 500, share: 0.9}, #" \
  "$src/config/teleop-falcon-sim.yaml" \
  | awk '/^ +sim:/ { skip = 1; next } skip && /^        / { next } { skip = 0; print }' > "$work/falcon-usb.yaml"
grep -qE "^ +transport: usb" "$work/falcon-usb.yaml" || { echo "config/teleop-falcon-sim.yaml changed: no transport: sim"; exit 1; }
[ "$(grep -c "deadline: {in_a_row: 500" "$work/falcon-usb.yaml")" = 3 ] ||
  { echo "config/teleop-falcon-sim.yaml changed: its three tasks' deadlines were not loosened"; exit 1; }
"$saw_rt" "$work/falcon-usb.yaml" --duration 10 > "$work/rt.out" 2> "$work/rt.err" &
rt=$!
for _ in $(seq 600); do grep -q '^homed' "$work/gadget.log" && break; kill -0 $rt 2> /dev/null || break; sleep 0.1; done
grep -q '^homed' "$work/gadget.log" || { echo "the Falcon never homed"; cat "$work/rt.out" "$work/rt.err"; exit 1; }
sleep 3  # teleoperation on the homed Falcon, then the device goes away mid-run
echo "" > /sys/kernel/config/usb_gadget/sawfalcon/UDC
rc=0
wait $rt || rc=$?
cat "$work/rt.out"
echo "--- saw-rt stderr"
cat "$work/rt.err"
kill -TERM "$gadget"
wait "$gadget" || true
[ "$rc" -eq 0 ] || { echo "saw-rt exited $rc"; exit 1; }
# The upload echoes the loader's probe byte, then the file's 4000 bytes.
grep -q "firmware_bytes=4001 " "$work/gadget.log" || { echo "the firmware was not uploaded whole"; exit 1; }
grep -q "homed=1" "$work/gadget.log" || { echo "the Falcon did not home"; exit 1; }
grep -qE "^  teleop: FAULT .*over [1-9][0-9]* enabled cycles" "$work/rt.out" ||
  { echo "the teleoperation never ran on the homed Falcon, or did not fault with it"; exit 1; }
grep -qE "error master: FAULT \(zero force\): usb .*\(device lost" "$work/rt.err" ||
  { echo "the unplug was not a FAULT with zero force saying the device was lost"; exit 1; }
grep -E "rate=" "$work/gadget.log"
