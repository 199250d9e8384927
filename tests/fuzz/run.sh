#!/usr/bin/env bash
# run.sh: runs the libFuzzer targets built by `cmake --preset fuzz && cmake --build --preset
# fuzz` (in build-fuzz/). From the repository root:
#
#   tests/fuzz/run.sh [SECONDS] [TARGET...]
#
# runs each TARGET (default: frame sidecar preset povray) for SECONDS (default 60) on a
# working corpus in build-fuzz/corpus/<target>/, which starts from the committed seeds in
# tests/fuzz/corpus/<target>/ and keeps what the fuzzer adds, with the target's dictionary.
# JOBS=N runs N fuzzing processes per target (default 1). Each target's log is
# build-fuzz/fuzz-<target>.log; a summary line per target gives the executions, the
# coverage (edges) and features reached, and the size of the corpus. A crash, leak,
# sanitizer report, timeout (over 10 s for one input), allocation over 2 GB or resident
# memory over 3 GB is a finding: the input that caused it is saved as
# build-fuzz/findings/<target>/, the log names it, and run.sh exits 1.
#
# The long campaign: JOBS=2 tests/fuzz/run.sh 3600 (an hour per target on 2 cores).
#
# A bounded run (what CI does): RUNS=N stops each target after N executions (each job after
# N with JOBS), SEED=S (default 1, one job only) fixes libFuzzer's random choices, and
# CORPUS=DIR puts the working corpora in DIR/<target>/ instead (a fresh DIR starts from the
# committed seeds alone). The inputs made then depend on the seed and little else, though
# not on it alone: coverage also sees the build's paths and threads. SECONDS still bounds it.
# Replaying one input: build-fuzz/tests/fuzz/fuzz_<target> FILE.
set -uo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-60}
shift || true
targets=("$@")
((${#targets[@]})) || targets=(frame sidecar preset povray)
jobs=${JOBS:-1}
B=$PWD/build-fuzz
status=0
for t in "${targets[@]}"; do
  bin=$B/tests/fuzz/fuzz_$t
  [ -x "$bin" ] || { echo "run.sh: $bin not built (cmake --preset fuzz && cmake --build --preset fuzz)" >&2; exit 2; }
  dict=$PWD/tests/fuzz/json.dict
  case $t in frame | povray) dict=$PWD/tests/fuzz/exr.dict ;; esac
  work=${CORPUS:-$B/corpus}/$t
  mkdir -p "$work" "$B/findings/$t"
  cp -n tests/fuzz/corpus/$t/* "$work/"
  log=$B/fuzz-$t.log
  args=(-max_total_time="$seconds" -timeout=10 -rss_limit_mb=3072 -malloc_limit_mb=2048
    -dict="$dict" -print_final_stats=1 -artifact_prefix="$B/findings/$t/")
  # RUNS is per job; each job of several takes a seed of its own.
  [ -n "${RUNS:-}" ] && args+=(-runs="$RUNS")
  [ -n "${RUNS:-}" ] && ((jobs == 1)) && args+=(-seed="${SEED:-1}")
  if ((jobs > 1)); then
    # -jobs writes one log per job (fuzz-<n>.log in the current folder, so run in $B),
    # kept as fuzz-<target>-job<n>.log: the parent's own log does not repeat a job that
    # stopped on a finding.
    rm -f "$B"/fuzz-[0-9]*.log "$B/fuzz-$t"-job*.log
    (cd "$B" && ASAN_OPTIONS=detect_leaks=1:quarantine_size_mb=64 "$bin" "${args[@]}" \
      -jobs="$jobs" -workers="$jobs" "$work" >"$log" 2>&1)
    rc=$?
    for j in "$B"/fuzz-[0-9]*.log; do
      [ -e "$j" ] && mv "$j" "$B/fuzz-$t-job$(basename "$j" .log | tr -dc 0-9).log"
    done
    logs=("$B/fuzz-$t"-job*.log)
  else
    ASAN_OPTIONS=detect_leaks=1:quarantine_size_mb=64 "$bin" "${args[@]}" "$work" >"$log" 2>&1
    rc=$?
    logs=("$log")
  fi
  execs=$(grep -ho 'stat::number_of_executed_units: [0-9]*' "${logs[@]}" | awk '{s += $2} END {print s + 0}')
  last=$(for l in "${logs[@]}"; do grep -hE '^#[0-9]+' "$l" | tail -1; done | sort -t: -k2 -n | tail -1)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
  n=$(find "$work" -type f | wc -l)
  took=$(sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p' "${logs[@]}" | sort -n | tail -1)
  if ((rc != 0)); then
    status=1
    echo "fuzz_$t: FINDING (exit $rc) after $execs executions; see ${logs[*]}"
    grep -hE 'ERROR|SUMMARY|Test unit written|fuzz_[a-z]*:' "${logs[@]}" | head -8
  else
    echo "fuzz_$t: $execs executions in ${took:-$seconds} s, ${cov:-?} edges, ${ft:-?} features, $n inputs in the corpus"
  fi
done
exit $status
