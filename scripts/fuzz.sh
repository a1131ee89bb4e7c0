#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, clang++, AddressSanitizer + UBSan) in ./build-fuzz and runs
# each in turn, one process, starting from the seeds in fuzz/corpus/<target>/.
#
#   bash scripts/fuzz.sh [SECONDS]          each target for SECONDS (default 15; CI: 7 x 15 s)
#   bash scripts/fuzz.sh -runs=1000000      each target for that many executions
#   FUZZ_TARGETS="fuzz_read_ply fuzz_graph" bash scripts/fuzz.sh 3600   only those
#
# Inputs the fuzzer finds interesting are kept in build-fuzz/corpus/<target>/ (not in the
# repository); a crash, leak, timeout (10 s) or out-of-memory (2 GB) stops with its input saved
# as build-fuzz/artifacts/<target>/crash-… and this script exits 1. Reproduce one with
#   build-fuzz/fuzz/<target> build-fuzz/artifacts/<target>/crash-…
set -euo pipefail
cd "$(dirname "$0")/.."
limit="-max_total_time=${1:-15}"
[[ "${1:-}" == -runs=* ]] && limit="$1"
bash scripts/install-deps.sh
# -O1 -gline-tables-only, as libFuzzer's documentation advises: quicker to build (CI builds this
# tree cold) and file and line in the reports.
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" \
  -DSCALLOP_FUZZ=ON -DSCALLOP_TESTS=OFF -DSCALLOP_BENCH=OFF >/dev/null
cmake --build build-fuzz -j "$(nproc)" --target scallop_fuzzers
targets=${FUZZ_TARGETS:-"fuzz_read_ply fuzz_read_pcd fuzz_read_text fuzz_read_off fuzz_read_obj fuzz_read_stl fuzz_read_mesh fuzz_graph"}
export ASAN_OPTIONS=detect_leaks=1:halt_on_error=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
failed=()
for t in $targets; do
  seeds=fuzz/corpus/${t#fuzz_read_}; [ "$t" = fuzz_graph ] && seeds=fuzz/corpus/graph
  mkdir -p "build-fuzz/corpus/$t" "build-fuzz/artifacts/$t"
  log="build-fuzz/$t.log"
  start=$(date +%s)
  if build-fuzz/fuzz/"$t" "build-fuzz/corpus/$t" "$seeds" "$limit" -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="build-fuzz/artifacts/$t/" >"$log" 2>&1; then
    status=ok
  else
    status=FAILED; failed+=("$t")
  fi
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  echo "$t: $status, $runs executions in $(( $(date +%s) - start )) s (log: $log)"
  if [ "$status" != ok ]; then grep -E 'ERROR|SUMMARY|Test unit written|==[0-9]+==' "$log" | head -20; fi
done
if ((${#failed[@]})); then echo "fuzzing found problems in: ${failed[*]}"; exit 1; fi
