#!/usr/bin/env bash
# The README's main job: installs what is missing, builds, and runs the simulated teleoperation
# deployment (config/teleop-sim.yaml) for 10 s at 1 kHz, then prints its summary.
# Extra arguments go to saw-rt (e.g. --duration 60, --stepped).
# --gui (first): the same deployment exported to its gateway (DDS domain 0, loopback), with sawgui
# beside it; it runs until the window is closed (or --duration), then saw-rt stops.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
if [[ "${1:-}" == "--gui" ]]; then
  shift
  tools/bootstrap.sh --tests  # sawgui: the venv (PySide6) and the X libraries its xcb plugin links
  tools/build.sh saw-rt saw-gateway
  yaml=build/teleop-sim-gui.yaml
  { cat config/teleop-sim.yaml
    printf '%s\n' "exports:" "  - {component: master, provided: arm}" "  - {component: slave, provided: arm}" \
      "  - {component: teleop, provided: teleop}" "gateway:" "  domain: 0"; } >"$yaml"
  build/release/bin/saw-rt "$yaml" "$@" &
  rt=$!
  PYTHONPATH="$root/nonrt/python" .venv/bin/python -m sawgui --domain 0 || true
  kill -TERM "$rt" 2>/dev/null || true
  wait "$rt" || true
  exit 0
fi
tools/build.sh saw-rt
exec build/release/bin/saw-rt config/teleop-sim.yaml --duration 10 --record build/teleop-sim.csv "$@"
