#!/usr/bin/env bash
# Runs the libFuzzer harnesses built by the `fuzz` preset (build/fuzz; see docs/fuzzing.md).
#
#   scripts/fuzz.sh smoke    every harness over its seeds (fuzz/corpus/<harness>/), then a few
#                            seconds of fuzzing from a fresh temporary working corpus; fails on
#                            any finding. FUZZ_SMOKE_SECONDS per harness (default 10).
#   scripts/fuzz.sh long     every harness for FUZZ_SECONDS (default 600), the working corpus
#                            kept in build/fuzz/corpus/<harness>/ (a run goes on from the last),
#                            findings in build/fuzz/findings/<harness>/, logs in build/fuzz/logs/.
#
# FUZZ_HARNESSES="map replay" runs only those; FUZZ_JOBS=N runs N harnesses at a time (default
# 1: the others on the machine keep a core); FUZZ_RUNS=N stops a harness after N inputs (the
# time still caps it). Each harness stops at its first finding; the script runs the rest and
# fails at the end if any found something.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build/fuzz"
all_harnesses=(map config scenario replay codec view_request bench_rows checkpoint text bench_folder scenario_folder)

mode="${1:-}"
case "$mode" in
  smoke) seconds="${FUZZ_SMOKE_SECONDS:-10}" ;;
  long) seconds="${FUZZ_SECONDS:-600}" ;;
  one) ;;  # internal: one harness (see below)
  *)
    echo "usage: scripts/fuzz.sh smoke|long (see the comment at the top)" >&2
    exit 2
    ;;
esac

# One harness: scripts/fuzz.sh one MODE SECONDS NAME. Prints one summary line; exit status 1
# on a finding.
run_one() {
  local mode="$1" seconds="$2" name="$3"
  local bin="$build/fuzz_$name" seeds="$root/fuzz/corpus/$name"
  local work findings log
  if [ ! -x "$bin" ]; then
    echo "fuzz: $bin is missing; build it with: cmake --preset fuzz && cmake --build --preset fuzz" >&2
    return 1
  fi
  if [ "$mode" = smoke ]; then
    work="$(mktemp -d "${TMPDIR:-/tmp}/overtake-fuzz-$name.XXXXXX")"
    findings="$build/smoke-findings/$name"
    log="$build/logs/smoke-$name.log"
  else
    work="$build/corpus/$name"
    findings="$build/findings/$name"
    log="$build/logs/$name.log"
  fi
  mkdir -p "$work" "$findings" "$(dirname "$log")"
  # -timeout: one input taking this long is a finding (a hang); -rss_limit_mb: so is memory
  # beyond it. New inputs go to the working corpus (the first directory), never to the seeds.
  local status=0 start=$SECONDS
  "$bin" -max_total_time="$seconds" -runs="${FUZZ_RUNS:--1}" -timeout=20 -rss_limit_mb=2048 \
    -print_final_stats=1 -artifact_prefix="$findings/" "$work" "$seeds" >"$log" 2>&1 ||
    status=$?
  local took=$((SECONDS - start))
  if [ "$mode" = smoke ]; then rm -rf "$work"; fi
  local runs rate
  runs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)"
  rate="$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)"
  if [ "$status" -ne 0 ]; then
    echo "fuzz $name: FINDING after ${runs:-?} runs (exit $status); log $log, input in $findings/"
    grep -m 3 -E '^==[0-9]+==ERROR|runtime error|^SUMMARY|deadly signal|Test unit written' "$log" |
      sed 's/^/  /' || true
    return 1
  fi
  echo "fuzz $name: ${runs:-?} runs in ${took} s (${rate:-?}/s), no finding"
}

if [ "$mode" = one ]; then
  run_one "$2" "$3" "$4"
  exit $?
fi

read -r -a harnesses <<<"${FUZZ_HARNESSES:-${all_harnesses[*]}}"
jobs="${FUZZ_JOBS:-1}"
echo "fuzz: $mode run, ${seconds} s per harness, ${jobs} at a time: ${harnesses[*]}"
# xargs returns 123 when any harness failed; every harness runs regardless.
if printf '%s\n' "${harnesses[@]}" |
  xargs -P "$jobs" -I{} "$0" one "$mode" "$seconds" {}; then
  echo "fuzz: no findings"
else
  echo "fuzz: FINDINGS (see above); reproduce one with: build/fuzz/fuzz_<harness> <input>"
  exit 1
fi
