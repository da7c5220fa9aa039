#!/usr/bin/env bash
# Reproduces the paper's Fig. 7 (tracking with delay, with and without prediction) into docs/.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
tools/bootstrap.sh --tests  # .venv (and what the tests and tools run: stress-ng, rt-tests, Xvfb...)
tools/build.sh saw-rt
exec .venv/bin/python tools/experiments/fig7.py "$@"
