#!/usr/bin/env bash
# Bilateral teleoperation under delay: the laws against delay, jitter and loss, into docs/.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
tools/bootstrap.sh --tests  # .venv (and what the tests and tools run: stress-ng, rt-tests, Xvfb...)
tools/build.sh saw-rt
exec .venv/bin/python tools/experiments/bilateral.py "$@"
