#!/usr/bin/env bash
# Fuzzes the readers of outside data with libFuzzer (tests/fuzz, docs/security.md "Hostile
# files"): builds the fuzz targets with clang into ./build-fuzz, runs each for SECONDS (default
# 300) on one core per job, and merges every input that reaches new code into the target's
# corpus in tests/fuzz/corpus/NAME (commit them: ctest replays the corpus under ASan/UBSan).
# A crash, hang, leak or sanitizer report leaves its input in build-fuzz/findings/NAME/ and makes
# the script exit 1 after the other targets ran.
#
#   deploy/fuzz.sh [SECONDS] [NAME...]     (NAME: scene_file gmsh_mesh ... ; default: all)
#
# Needs clang and libFuzzer (Debian 12: clang, libclang-rt-14-dev); set HANDSHARE_JOBS for more
# than 2 targets at a time.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-300}"
shift || true
all=(scene_file gmsh_mesh abaqus_mesh tetgen_mesh load_case hand_script replay_trace hiro_config session_log recording)
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=("${all[@]}")
for t in "${targets[@]}"; do
  [ -d "tests/fuzz/corpus/$t" ] || { echo "fuzz.sh: no fuzz target '$t' (known: ${all[*]})" >&2; exit 2; }
done
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ not found (apt-get install clang libclang-rt-14-dev)" >&2; exit 2; }

cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DHANDSHARE_FUZZ=ON -DHANDSHARE_WARNINGS_AS_ERRORS=OFF -DHANDSHARE_BUILD_BENCH=OFF ${HANDSHARE_CMAKE_ARGS:-} >/dev/null
cmake --build build-fuzz -j "${HANDSHARE_JOBS:-2}" --target $(printf 'fuzz_%s ' "${targets[@]}")

status=0
run() {
  local t="$1" work="build-fuzz/corpus/$1" findings="build-fuzz/findings/$1"
  mkdir -p "$work" "$findings"
  # New inputs go to the work corpus; the repository's corpus seeds it and is read only here.
  if ! "build-fuzz/tests/fuzz/fuzz_$t" "$work" "tests/fuzz/corpus/$t" -max_total_time="$seconds" -timeout=10 \
       -rss_limit_mb=2048 -max_len=131072 -artifact_prefix="$findings/" -print_final_stats=1 \
       >"build-fuzz/fuzz_$t.log" 2>&1; then
    echo "fuzz.sh: $t: a finding, in $findings/ (log: build-fuzz/fuzz_$t.log)"
    return 1
  fi
  # Keep only inputs that add coverage to what the repository's corpus already reaches.
  "build-fuzz/tests/fuzz/fuzz_$t" -merge=1 "tests/fuzz/corpus/$t" "$work" >>"build-fuzz/fuzz_$t.log" 2>&1
  echo "fuzz.sh: $t: $(grep -o 'stat::number_of_executed_units: *[0-9]*' "build-fuzz/fuzz_$t.log" | tail -1 |
    grep -o '[0-9]*$') runs in ${seconds} s, no finding; corpus $(ls "tests/fuzz/corpus/$t" | wc -l) files"
}
jobs_max="${HANDSHARE_JOBS:-2}"
pids=()
for t in "${targets[@]}"; do
  run "$t" &
  pids+=($!)
  while [ "$(jobs -rp | wc -l)" -ge "$jobs_max" ]; do sleep 1; done
done
for p in "${pids[@]}"; do wait "$p" || status=1; done
exit $status
