#!/usr/bin/env bash
# One check of the PREEMPT_RT guest as a CTest test: prints RESULTS/NAME.log and exits 0 if the
# guest wrote `pass` for it, 1 if it wrote a failure or nothing, 77 (skip) if the guest could
# not be booted here (RESULTS/skipped says why). Usage: result.sh RESULTS NAME
set -euo pipefail
out=$1
name=$2
if [ -e "$out/skipped" ]; then
  echo "SKIP: the guest was not booted: $(cat "$out/skipped")"
  exit 77
fi
[ -e "$out/$name.log" ] && tail -c 20000 "$out/$name.log"
if [ ! -e "$out/$name.result" ]; then
  echo "FAIL: the guest reported nothing for $name (see Kernel.Boot and $out/console.log)"
  exit 1
fi
result=$(cat "$out/$name.result")
echo "$name: $result"
[ "$result" = pass ]
