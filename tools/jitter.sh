#!/usr/bin/env bash
# One command: sawrt's 1 kHz wake-up latency beside cyclictest, idle and under stress-ng load,
# as a Markdown table (also in build/jitter/table.md), histograms in cyclictest's format and
# PNG overlays in docs/img/. Extra arguments go to saw-jitter (e.g. --duration 600).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
tools/bootstrap.sh --tests  # .venv (and what the tests and tools run: stress-ng, rt-tests, Xvfb...)
tools/build.sh saw-jitter
mkdir -p build/jitter docs/img
build/release/tools/bench/saw-jitter --load --markdown --out build/jitter "$@" | tee build/jitter/table.md
.venv/bin/python tools/plot_jitter.py build/jitter docs/img/jitter
