#!/usr/bin/env bash
# One command: runs every benchmark of sawrt on this machine and rewrites docs/performance.md
# (machine, kernel, date, commands, tables, goals) and the plots in docs/img/. Takes about 8
# minutes; --quick (about 3) shortens the jitter runs and the benchmark loops for a first look;
# --can runs only the CANopen benchmark (about 15 s) and rewrites only its section; --gui runs only
# the remote GUIs' benchmarks (about 4 minutes: the headless subscribers, then the window) and
# rewrites only their sections.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
quick=0 can_only=0 gui_only=0
[[ "${1:-}" == "--quick" ]] && quick=1
[[ "${1:-}" == "--can" ]] && can_only=1
[[ "${1:-}" == "--gui" ]] && gui_only=1
tools/bootstrap.sh --tests  # .venv (plots, the GUI benchmarks), stress-ng and cyclictest (jitter)
bin=build/release/tools/bench
run() {  # name, command...: the command line and its output into $out/name.{cmd,md}
  local name=$1; shift
  echo "== $name: $*" >&2
  echo "$*" >"$out/$name.cmd"
  "$@" >"$out/$name.md" 2>"$out/$name.err" || echo "exit $?" >>"$out/$name.md"
}
# CANopen on the virtual bus (saw-can-sim runs the drives): 2 rounds of 1 s per drive count and
# 4 s of teleoperation, about 15 s in all.
can_rounds=2 can_e2e=4
if ((quick)); then can_rounds=1 can_e2e=2; fi
# Remote GUIs: 0, 1 and 10 headless sawgui subscribers beside the 1 kHz teleoperation, alternating
# for 3 rounds of 15 s each (about 3.5 minutes).
gui_seconds=15 gui_rounds=3
if ((quick)); then gui_seconds=8 gui_rounds=1; fi
gui_run() {
  run gui .venv/bin/python tools/gui_scale.py build/release/bin/saw-rt build/release/bin/saw-gateway \
    --seconds $gui_seconds --rounds $gui_rounds --json $out/gui.json
  # The window itself (Xvfb): redraws, command latency, CPU with the Teleoperation tab open.
  run window .venv/bin/python tools/gui_perf.py build/release/bin/saw-rt --seconds 10 --rounds 5 \
    --json $out/window.json
}
if ((gui_only)); then
  tools/build.sh saw-rt saw-gateway
  out=build/perf-gui
  rm -rf "$out" && mkdir -p "$out"
  gui_run
  .venv/bin/python tools/write_performance.py $out docs/performance.md --only gui
  echo "rewrote the remote GUIs section of docs/performance.md" >&2
  exit 0
fi
if ((can_only)); then
  tools/build.sh saw-bench-can saw-can-sim
  out=build/perf-can
  rm -rf "$out" && mkdir -p "$out"
  run can $bin/saw-bench-can --rounds $can_rounds --e2e-seconds $can_e2e --json $out/can.json
  .venv/bin/python tools/write_performance.py $out docs/performance.md --only can
  echo "rewrote the CANopen section of docs/performance.md" >&2
  exit 0
fi
tools/build.sh saw-rt saw-gateway saw-bench-core saw-bench-shm saw-bench-2p saw-latency saw-jitter saw-gateway-kill \
  saw-bench-can saw-can-sim
out=build/perf
rm -rf "$out" && mkdir -p "$out" docs/img
calls=10000 jitter=60 e2e=10 rounds=10
if ((quick)); then calls=2000 jitter=10 e2e=5 rounds=3; fi
run core $bin/saw-bench-core --markdown --calls $calls
run shm $bin/saw-bench-shm --markdown --calls $calls
run local2p $bin/saw-bench-2p --markdown --calls $calls
run latency $bin/saw-latency --calls $calls --csv $out/latency.csv
run jitter $bin/saw-jitter --load --markdown --duration $jitter --out $out/jitter
run gateway_kill $bin/saw-gateway-kill --rounds $rounds
run can $bin/saw-bench-can --rounds $can_rounds --e2e-seconds $can_e2e --json $out/can.json
gui_run
run e2e_one build/release/bin/saw-rt config/teleop-sim.yaml --duration $e2e
# Two processes: the operator's side (master) and the patient's side (slave + teleoperation).
echo "build/release/bin/saw-rt config/teleop-sim-hosts.yaml --host operator & ... --host patient" >$out/e2e_two.cmd
build/release/bin/saw-rt config/teleop-sim-hosts.yaml --host operator --duration $((e2e + 2)) >$out/e2e_operator.md 2>&1 &
operator=$!
sleep 0.5
build/release/bin/saw-rt config/teleop-sim-hosts.yaml --host patient --duration $e2e >$out/e2e_two.md 2>&1 || true
wait $operator || true
.venv/bin/python tools/plot_latency.py $out/latency.csv docs/img/latency.png
.venv/bin/python tools/plot_jitter.py $out/jitter docs/img/jitter
.venv/bin/python tools/write_performance.py $out docs/performance.md
echo "wrote docs/performance.md" >&2
