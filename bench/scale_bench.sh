#!/usr/bin/env bash
# Benchmark of large clouds (issue 15): the zig-zag graph on the catalog's waves surface at each
# size given, cold (empty disk cache), warm (everything cached), and again with only the scallop
# limit, then only the tool radius changed (what depends on them reruns). For each run: wall time
# and peak memory of the whole process; for the cold one every node's wall time and peak resident
# memory (the process's high-water mark while the node ran), next to the library floors
# (bench/library_floors.cpp) measured in the same run on the same cloud, and the ratio of the whole
# cold run to the floors' sum.
#   bench/scale_bench.sh [N ...]          default: 100000 1000000
#   GRAPH=graphs/isoparametric-contour.json SURFACE=dome bench/scale_bench.sh 100000
set -euo pipefail
cd "$(dirname "$0")/.."
graph=${GRAPH:-graphs/isoparametric-zigzag.json}
surface=${SURFACE:-waves}
tools=${SCALLOP_TOOLS:-../shared/tools}
work=${BENCH_DIR:-/tmp/scallop-bench}
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(100000 1000000)
mkdir -p "$work"
for n in "${sizes[@]}"; do
  cloud="$work/${surface}_${n}.ply"
  [ -f "$cloud" ] || /usr/bin/python3 "$tools/make_cloud.py" --surface "$surface" --n "$n" --seed 1 -o "$cloud"
  echo "=== $surface, $n points, $graph"
  ./build/library_floors "$cloud" 16 | tee "$work/floors-$n.txt"
  rm -rf "$work/cache-$n"
  run() {  # label, then --set items
    local label=$1
    shift
    local status=0
    /usr/bin/time -f "%e %M" -o "$work/time.txt" ./build/scallop run "$graph" --input cloud="$cloud" \
      --cache "$work/cache-$n" -o "$work/out-$n" -q --events "$work/events-$n-$label.jsonl" "$@" \
      >/dev/null 2>"$work/stderr-$n-$label.txt" || status=$?
    read -r wall rss <"$work/time.txt"
    # The run's own peak (the largest of its nodes'): /usr/bin/time's is only since the last
    # node that started with none running (the executor restarts the high-water mark there).
    local peak
    peak=$(sed -n 's/.*, peak \([0-9]*\) MiB$/\1/p' "$work/stderr-$n-$label.txt" | tail -1)
    [ -n "$peak" ] || peak=$((rss / 1024))
    printf '%-22s wall %8.2f s   peak %6d MiB   exit %d\n' "$label" "$wall" "$peak" "$status"
    echo "$wall" >"$work/wall-$n-$label.txt"
  }
  run cold
  /usr/bin/python3 - "$work/events-$n-cold.jsonl" "$work/floors-$n.txt" "$work/wall-$n-cold.txt" <<'PY'
import json, sys
print(f'   {"node":<14} {"type":<22} {"seconds":>8} {"peak MiB":>9}')
for line in open(sys.argv[1]):
    e = json.loads(line)
    if e["event"] == "node_finish":
        print(f'   {e["node"]:<14} {e["type"]:<22} {e["seconds"]:8.3f} {e.get("peak_mib", 0):9.0f}')
floors = {l.split()[1]: float(l.split()[2]) for l in open(sys.argv[2]) if l.startswith("floor")}
wall = float(open(sys.argv[3]).read())
print(f'   whole cold run / library floors: {wall:.2f} / {floors["sum"]:.2f} = {wall / floors["sum"]:.1f}x')
# issue 15's goal: the run is at most 2x the floors plus the planner, guard and simulation
own = sum(json.loads(l)["seconds"] for l in open(sys.argv[1])
          if json.loads(l)["event"] == "node_finish"
          and json.loads(l)["type"] in ("path.isoparametric", "path.gouge_guard", "post.simulate"))
print(f'   without planner, guard and simulation ({own:.2f} s): {wall - own:.2f} / {floors["sum"]:.2f} = '
      f'{(wall - own) / floors["sum"]:.1f}x (goal <= 2x)')
PY
  run warm
  run scallop_height=0.04 --set scallop_height=0.04
  # What the rerun loads from the cache and what it computes again, node by node (a cached node's
  # time is its entry's load: size on disk beside it).
  /usr/bin/python3 - "$work/events-$n-scallop_height=0.04.jsonl" "$work/cache-$n" <<'PY'
import json, os, sys
print(f'   {"node":<14} {"type":<22} {"seconds":>8} {"from":>6} {"entry MiB":>10}')
for line in open(sys.argv[1]):
    e = json.loads(line)
    if e["event"] != "node_finish" or e["seconds"] < 0.01:
        continue
    entry = os.path.join(sys.argv[2], e["key"][:2], e["key"] + ".entry")
    size = f'{os.path.getsize(entry) / 2**20:10.0f}' if e["status"] == "cached" and os.path.exists(entry) else ""
    print(f'   {e["node"]:<14} {e["type"]:<22} {e["seconds"]:8.3f} {"cache" if e["status"] == "cached" else "run":>6} {size}')
PY
  run tool_radius=3 --set scallop_height=0.04 --set tool_radius=3
done
