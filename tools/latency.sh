#!/usr/bin/env bash
# One command: saw-latency, the paper's Fig. 4 qualified-read benchmark in every configuration
# (Local 1P, Local 2P over shared memory and over DDS, Network 1H across a veth pair, Network MH
# across a router) beside
# ZeroC Ice and raw Fast DDS; a Markdown table (build/latency/table.md), CSV and
# docs/img/latency.png. Extra arguments go to saw-latency (e.g. --calls 2000, --no-veth).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
tools/bootstrap.sh --tests  # .venv (and what the tests and tools run: stress-ng, rt-tests, Xvfb...)
tools/build.sh saw-latency
mkdir -p build/latency docs/img
build/release/tools/bench/saw-latency --csv build/latency/table.csv "$@" | tee build/latency/table.md
.venv/bin/python tools/plot_latency.py build/latency/table.csv docs/img/latency.png
