#!/usr/bin/env bash
# Installs what is missing and builds the release preset: every target, or the ones named.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
tools/bootstrap.sh
cmake --preset release >/dev/null
if (($#)); then
  cmake --build --preset release --target "$@"
else
  cmake --build --preset release
fi
