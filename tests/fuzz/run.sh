#!/usr/bin/env bash
# Runs the fuzz targets (libFuzzer, the `fuzz` preset) for a bounded time each, from their corpus.
#   tests/fuzz/run.sh                      every target, 60 s each
#   tests/fuzz/run.sh --time 3600 [name…]  longer, or only the targets named (e.g. deploy_yaml)
#   tests/fuzz/run.sh --runs N --seed S     N inputs each from seed S: the same run on any machine
#                                           (CI: what passed before landing passes in CI)
# New inputs go to build/fuzz/corpus/<target>/ (not committed); a crash leaves its input in
# build/fuzz/crash-<target>-*: copy it into tests/fuzz/<target>/ once fixed (a regression test).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
seconds=60
runs=-1
seed=0
targets=()
while (($#)); do
  case $1 in
    --time) seconds=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
((${#targets[@]})) || targets=(bridge_segment deploy_yaml gateway_sample can_frames canopen_eds)

cmake --preset fuzz >/dev/null
cmake --build --preset fuzz --target "${targets[@]/#/fuzz_}"  # only what runs here
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
out=build/fuzz
failed=()
for t in "${targets[@]}"; do
  mkdir -p "$out/corpus/$t"
  args=(-max_total_time="$seconds" -runs="$runs" -seed="$seed" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1
        -artifact_prefix="$out/crash-$t-")
  [ -f "tests/fuzz/$t.dict" ] && args+=(-dict="tests/fuzz/$t.dict")
  [ "$t" = bridge_segment ] && args+=(-max_len=16384)  # a whole small segment (two pages at least)
  echo "== fuzz $t: $seconds s at most$( ((runs >= 0)) && echo ", $runs inputs from seed $seed")"
  if "$out/tests/fuzz/fuzz_$t" "${args[@]}" "$out/corpus/$t" "tests/fuzz/$t" >"$out/$t.log" 2>&1; then
    grep -E "^#[0-9]+[[:space:]]+DONE|stat::number_of_executed_units|stat::peak_rss_mb" "$out/$t.log" || true
  else
    failed+=("$t")
    tail -n 60 "$out/$t.log"
    ls "$out"/crash-"$t"-* 2>/dev/null || true
  fi
done
if ((${#failed[@]})); then
  echo "fuzz: crashed: ${failed[*]} (inputs in $out/crash-*, logs in $out/<target>.log)" >&2
  exit 1
fi
