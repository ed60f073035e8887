#!/usr/bin/env bash
# Runs the whole cross-process suite (ctest -L integration) N times in a row while other
# processes keep every core busy, to show that the tests wait on events, not on luck with
# timing. Prints PASS/FAIL per run (with the failing tests) and a total; exits 0 only if every
# run passed. The load runs at normal priority, like another engineer's build. A failing run's
# work folders (those its output names) are copied beside its log: the next run reuses them.
#
# usage: tests/repeat_suite.sh [N] [BUILD_DIR]   (defaults: 20, build)
#   LOAD_PROCS=k   busy loops to start (default: the number of cores)
#   LOG_DIR=dir    where each run's ctest output goes (default: BUILD_DIR/repeat_suite)
set -uo pipefail
cd "$(dirname "$0")/.."
runs="${1:-20}"
build="${2:-build}"
load_procs="${LOAD_PROCS:-$(nproc)}"
log_dir="${LOG_DIR:-$build/repeat_suite}"
mkdir -p "$log_dir"
work_root="$(realpath "$build")/tests/work"

load_pids=()
stop_load() {
  for p in "${load_pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${load_pids[@]}"; do wait "$p" 2>/dev/null || true; done
  load_pids=()
}
trap stop_load EXIT
trap 'exit 130' INT TERM
for ((k = 0; k < load_procs; ++k)); do
  # A pure CPU loop (no output, no memory): the shell's own arithmetic, forever.
  bash -c 'while :; do :; done' &
  load_pids+=($!)
done
echo "repeat_suite: $runs runs of ctest -L integration in $build, $load_procs busy loops (pids ${load_pids[*]})"

passed=0
for ((run = 1; run <= runs; ++run)); do
  log="$log_dir/run_$run.log"
  start=$(date +%s)
  if ctest --test-dir "$build" -L integration --output-on-failure > "$log" 2>&1; then
    passed=$((passed + 1))
    echo "run $run: PASS ($(( $(date +%s) - start )) s)"
  else
    failed=$(grep -E '^\s+[0-9]+ - ' "$log" | sed -E 's/^\s+[0-9]+ - //' | tr '\n' ' ')
    echo "run $run: FAIL ($(( $(date +%s) - start )) s): ${failed:-see $log} (log: $log)"
    # The next run reuses the work folders: keep the ones the failure output names (frames,
    # node logs, recordings) before they are overwritten.
    keep="$log_dir/run_${run}_work"
    grep -oE "$work_root/[A-Za-z0-9_.-]+" "$log" | sort -u | grep -v '/fem_cache$' | while read -r dir; do
      [ -d "$dir" ] && mkdir -p "$keep" && cp -a "$dir" "$keep/"
    done
    [ -d "$keep" ] && echo "run $run: kept $(ls "$keep" | tr '\n' ' ')in $keep"
  fi
done
echo "repeat_suite: $passed of $runs runs passed"
[ "$passed" -eq "$runs" ]
