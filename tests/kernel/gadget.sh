#!/usr/bin/env bash
# Sourced in the PREEMPT_RT guest: gadget_up WORK starts tests/kernel/falcon_gadget.py (a Falcon
# played as a USB gadget on dummy_hcd; its log WORK/gadget.log), waits until the host side has
# enumerated it, and sets `gadget` to its pid; WORK/firmware.bin is a firmware file for it.
# gadget_down stops it and prints its log. Needs $src.

gadget_up() {
  local work=$1
  modprobe dummy_hcd is_high_speed=0 2> /dev/null || modprobe dummy_hcd
  modprobe libcomposite
  modprobe usb_f_fs
  mountpoint -q /sys/kernel/config || mount -t configfs none /sys/kernel/config
  head -c 4000 /dev/urandom > "$work/firmware.bin"  # the gadget echoes it: any content will do
  python3 "$src/tests/kernel/falcon_gadget.py" > "$work/gadget.log" 2>&1 &
  gadget=$!
  gadget_log=$work/gadget.log
  for _ in $(seq 200); do grep -q '^ready' "$work/gadget.log" && break; sleep 0.1; done
  grep -q '^ready' "$work/gadget.log" || { echo "the gadget did not come up"; return 1; }
  # The host side enumerates it: wait for 0403:cb48 on the bus.
  for _ in $(seq 300); do grep -lqs cb48 /sys/bus/usb/devices/*/idProduct && break; sleep 0.1; done
  grep -lqs cb48 /sys/bus/usb/devices/*/idProduct || { echo "0403:cb48 never enumerated"; return 1; }
}

gadget_down() {
  kill -TERM "$gadget" 2> /dev/null || true
  wait "$gadget" 2> /dev/null || true
  echo "--- gadget"
  cat "$gadget_log"
}
