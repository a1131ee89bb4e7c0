#!/usr/bin/env bash
# Benchmark: one graph on a catalog surface cloud made by ../shared/tools/make_cloud.py.
# Prints wall time, peak memory and per-node times for a cold run (empty disk cache) and a warm run.
#   bench/run_graph_bench.sh GRAPH SURFACE N [--set ...]
# e.g. bench/run_graph_bench.sh graphs/prepare-cloud.json waves 1000000
set -euo pipefail
cd "$(dirname "$0")/.."
graph=$1 surface=$2 n=$3
shift 3
tools=${SCALLOP_TOOLS:-../shared/tools}
work=${BENCH_DIR:-/tmp/scallop-bench}
mkdir -p "$work"
cloud="$work/${surface}_${n}.ply"
[ -f "$cloud" ] || /usr/bin/python3 "$tools/make_cloud.py" --surface "$surface" --n "$n" --seed 1 -o "$cloud"
rm -rf "$work/cache"
for label in cold warm; do
  /usr/bin/time -f "%e %M" -o "$work/time.txt" ./build/scallop run "$graph" --input cloud="$cloud" \
    --cache "$work/cache" -o "$work/out" -q --events "$work/events-$label.jsonl" "$@" >/dev/null
  read -r wall rss <"$work/time.txt"
  echo "== $label run: wall ${wall} s, peak memory $((rss / 1024)) MiB"
  /usr/bin/python3 - "$work/events-$label.jsonl" <<'PY'
import json, sys
for line in open(sys.argv[1]):
    e = json.loads(line)
    if e["event"] == "node_finish":
        print(f'   {e["node"]:<14} {e["type"]:<22} {e["status"]:<8} {e["seconds"]:8.3f} s')
PY
done
