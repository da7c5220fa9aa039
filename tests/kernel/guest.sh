#!/usr/bin/env bash
# Runs inside the PREEMPT_RT guest that tests/kernel/run.sh boots (the host's root, read-only):
# every kernel-level check in one boot. Each check writes RESULTS/NAME.result (`pass`, or
# `fail: why`) and RESULTS/NAME.log; RESULTS/done says the guest got to the end.
# Usage: guest.sh SRC RESULTS (RESULTS/targets.env names the built programs).
set -euo pipefail
src=$1
out=$2
set -a  # the programs' paths, and src and out, for the checks (each runs in a child bash)
# shellcheck disable=SC1091
source "$out/targets.env"
set +a
export src out
cut -d' ' -f1 /proc/uptime > "$out/boot-seconds"  # the kernel's uptime when the checks begin
cd /tmp  # writable here (an overlay); the programs may leave files in their working directory

# check NAME TIMEOUT COMMAND...: runs COMMAND, its output to NAME.log, exit 0 = pass.
check() {
  local name=$1 limit=$2
  shift 2
  local rc=0
  # shellcheck disable=SC2016
  timeout --kill-after=10 "$limit" bash -c '"$@"' "$name" "$@" > "$out/$name.log" 2>&1 || rc=$?
  if [ "$rc" -eq 0 ]; then
    echo pass > "$out/$name.result"
  elif [ "$rc" -eq 124 ]; then
    echo "fail: no answer within ${limit} s" > "$out/$name.result"
  else
    echo "fail: exit $rc (see $name.log)" > "$out/$name.result"
  fi
  echo "$name: $(cat "$out/$name.result")"
}

kernel_is_preempt_rt() {
  uname -a
  grep -q PREEMPT_RT <(uname -v) || { echo "uname -v does not say PREEMPT_RT"; return 1; }
  grep -qx "CONFIG_PREEMPT_RT=y" "/boot/config-$(uname -r)" ||
    { echo "/boot/config-$(uname -r) has no CONFIG_PREEMPT_RT=y"; return 1; }
}

# The main job on this kernel: the summary must name it PREEMPT_RT, and the tasks must have had
# SCHED_FIFO and locked memory (saw-rt warns on stderr otherwise).
saw_rt_teleop_sim() {
  local rc=0
  "$saw_rt" "$src/config/teleop-sim.yaml" --duration 2 > stdout.txt 2> stderr.txt || rc=$?
  cat stdout.txt
  echo "--- stderr"
  cat stderr.txt
  [ "$rc" -eq 0 ] || { echo "saw-rt exited $rc"; return 1; }
  grep -q "^summary of 'teleop-sim'" stdout.txt || { echo "no run summary"; return 1; }
  grep -qE "^  kernel: .*PREEMPT_RT.*\(PREEMPT_RT\)$" stdout.txt ||
    { echo "the summary does not name a PREEMPT_RT kernel"; return 1; }
  if grep -q "without full real-time guarantees" stderr.txt; then
    echo "saw-rt did not get real-time scheduling"
    return 1
  fi
  grep -qE "^  master +1\.00ms +[1-9]" stdout.txt || { echo "the master task did not cycle"; return 1; }
}

# The conformance suite of the SocketCAN backend on vcan0: none of it may skip here.
socketcan_conformance() {
  local rc=0
  SAW_TEST_CAN_INTERFACE=vcan0 "$saw_can_tests" --gtest_filter='Backends/BusConformance.*/socketcan:SocketCan*' \
    > conformance.txt 2>&1 || rc=$?
  cat conformance.txt
  [ "$rc" -eq 0 ] || return 1
  grep -qE "^\[  PASSED  \] [1-9][0-9]* tests?" conformance.txt || { echo "no test passed"; return 1; }
  # gtest lists each skipped test under this heading.
  if grep -q "^\[  SKIPPED \]" conformance.txt; then
    echo "a SocketCAN test skipped on vcan0"
    return 1
  fi
}

# The RT guard tests (allocations, locks, waits, page faults on RT threads), the CAN ones included:
# with AF_CAN here, the SocketCAN send/receive guard test runs on vcan0 (CAN_RAW sockets, where the
# host can only skip it), and must be seen to pass, not merely not to fail.
# Left out here: the continuous (busy-looping) SCHED_FIFO task tests. On two emulated CPUs such a
# task once kept the PREEMPT_RT guest from finishing the test (its main thread never returned, and
# neither did `timeout`); they run in the release suite on the host.
guard() {
  local rc=0
  "$saw_guard_tests" --gtest_filter='-RtGuard.*Continuous*' > guard.txt 2>&1 || rc=$?
  cat guard.txt
  # A guard test skips where it cannot check everything (no mlockall, no SCHED_FIFO): not here.
  grep -q "^\[  SKIPPED \]" guard.txt && { echo "a guard test skipped"; rc=1; }
  SAW_TEST_CAN_INTERFACE=vcan0 "$saw_can_guard_tests" > can_guard.txt 2>&1 || rc=$?
  cat can_guard.txt
  grep -q "^\[  SKIPPED \]" can_guard.txt && { echo "a CAN guard test skipped"; rc=1; }
  local af_can=CanRtGuard.SocketCanSendAndReceiveAreRtCleanOnAfCan
  grep -qF "[       OK ] $af_can (" can_guard.txt ||
    { echo "$af_can did not pass on vcan0 (AF_CAN)"; rc=1; }
  return "$rc"
}

export -f kernel_is_preempt_rt saw_rt_teleop_sim socketcan_conformance guard
echo "guest: $(uname -r) $(uname -v), $(nproc) CPUs, up $(cat "$out/boot-seconds") s"
check kernel.preempt_rt 30 kernel_is_preempt_rt
check saw_rt.teleop_sim 120 saw_rt_teleop_sim
# The Falcon over real USB: a gadget on dummy_hcd plays it (tests/kernel/falcon_gadget.py).
check falcon.usb 150 "$src/tests/kernel/falcon_usb.sh" "$src" "$saw_rt"

vcan_up() {
  modprobe vcan
  ip link add dev vcan0 type vcan
  ip link set vcan0 mtu 72  # CAN FD
  ip link set vcan0 up
  ip -details link show vcan0
}
export -f vcan_up
check can.vcan0 30 vcan_up
if [ "$(cat "$out/can.vcan0.result")" = pass ]; then
  check can.conformance 120 socketcan_conformance
  # Under software emulation the 1 kHz cycles stall for tens of ms: the arm's tracking bound is
  # loosened there (an arm that does not follow shows about 21 mm RMS; the drives must move).
  rms=15
  [ "$(cat "$out/accelerator" 2>/dev/null)" = kvm ] || rms=18
  check canopen.teleop 240 env SAW_TEST_CANOPEN_BUS=socketcan:vcan0 SAW_TEST_CANOPEN_MAX_RMS_MM=$rms python3 \
    "$src/tests/canopen/system/canopen_sim_teleop.py" "$saw_rt" "$saw_can_sim" "$src/config/canopen-sim.yaml"
  # One bus task, an arm and a gripper's I/O node as its clients (config/canopen-shared-bus.yaml),
  # saw-can-sim playing every node, on SocketCAN.
  check canopen.shared_bus 180 env SAW_TEST_CANOPEN_BUS=socketcan:vcan0 python3 \
    "$src/tests/canopen/system/canopen_shared_bus_sim.py" "$saw_rt" "$saw_can_sim" \
    "$src/config/canopen-shared-bus.yaml"
  check guard 120 guard
  # The soak's CAN bus down/up and Falcon unplug/replug, on vcan0 and the USB gadget.
  check soak.guest 300 "$src/tests/kernel/soak_guest.sh" "$src" "$saw_rt"
  # Last: it takes vcan0 down and up again. Writes one result per check (can.classic, ...).
  check can.peers 240 "$src/.venv/bin/python" "$src/tests/kernel/can_peers.py" "$can_side" vcan0 "$out"
else
  for c in can.conformance canopen.teleop canopen.shared_bus guard soak.guest can.peers; do echo "fail: no vcan0 (can.vcan0.log)" > "$out/$c.result"; done
fi
# After the timing-judged checks (its namespaces and DDS processes cost the emulated CPUs):
# beyond one subnet over a real impaired link: the routed namespaces of the host's test, the
# patient's link a wireless hop shaped by netem both ways (this kernel has it; the host's has not).
check net.routed_netem 300 python3 "$src/tests/interop/routed_peers.py" "$saw_rt" "$sawctl" \
  "$src/.venv/bin/python" --netem "delay 20ms 5ms loss 1% rate 20mbit" --patience 3 --brief
# The paper's Fig. 4 across that router with the patient's link a netem hop (Network MH): the
# DDS peer and the state row through both gateways beside raw Fast DDS and Ice over the same path,
# in one run (ratios of the same run only: emulated CPUs). Each of those rows must be measured
# with no call lost. The qualified read through both gateways is printed, not required here:
# under emulation the mirror's 1 kHz state stream runs ~100 ms behind and its queries time out
# (docs/performance.md, Network MH); on the host's suite and benchmarks it is measured.
latency_mh() {
  local rc=0
  [ -n "${saw_latency:-}" ] || { echo "saw-latency was not built (SAW_BUILD_TOOLS, SAW_WITH_ICE)"; return 1; }
  "$saw_latency" --no-local --no-veth --no-secure --calls 200 --reps 1 --rows 200 --gateway-cpu -1 \
    --netem "delay 1ms 200us" > latency.md || rc=$?
  cat latency.md
  echo "saw-latency exited $rc"
  local path row bad=0
  for path in "qualified read, DDS peer" "raw Fast DDS" "ZeroC Ice" \
    "state row, server task -> client process via both"; do
    row=$(grep "^| Network MH netem | $path" latency.md) || { echo "no Network MH netem row: $path"; bad=1; continue; }
    # | config | path | transport | median | p90 | p99 | p99.9 | max | n | failed |
    awk -F'|' '{ n = $10 + 0; f = $11 + 0; exit !(n > 0 && f == 0) }' <<< "$row" ||
      { echo "not measured, or calls lost: $row"; bad=1; }
  done
  # Any other failed path fails the check too.
  if grep "^| Network MH netem |" latency.md | grep -v "qualified read, both gateways" |
    awk -F'|' '$11 + 0 > 0 { found = 1 } END { exit !found }'; then
    echo "another path lost calls"
    bad=1
  fi
  return "$bad"
}
export -f latency_mh
check net.latency_mh 300 latency_mh
date > "$out/done"
