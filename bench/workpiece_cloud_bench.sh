#!/usr/bin/env bash
# Benchmark of a whole part from its cloud (issue 14: "a 200 000-point cloud to all programs in
# <= 90 s"): the bundled domed block sampled into N clean points (examples/make_part.py --cloud,
# the project's own code: no ../shared needed) through graphs/workpiece-contour.json, cold (no
# disk cache), as README's third example runs it (smooth=0, denoise=none, exact_edges). Prints
# every node's wall time and peak resident memory, when the last program was written (the
# programs node's end) and when the whole run ended (certificate, pictures and setup sheet too).
#   bench/workpiece_cloud_bench.sh [N ...]      default: 200000
#   R=2 H=0.02 E=0.005 bench/workpiece_cloud_bench.sh 200000    (the issue's settings)
# R, H and E: tool radius, scallop limit, chord tolerance (default the graph's 3, 0.05, 0.01 mm).
set -euo pipefail
cd "$(dirname "$0")/.."
work=${BENCH_DIR:-/tmp/scallop-workpiece-bench}
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(200000)
mkdir -p "$work"
for n in "${sizes[@]}"; do
  cloud="$work/domed_block_$n.ply"
  [ -f "$cloud" ] || python3 examples/make_part.py --cloud "$n" -o "$cloud" >/dev/null
  echo "=== domed block, $n points, graphs/workpiece-contour.json, r ${R:-3} h ${H:-0.05} e ${E:-0.01}"
  status=0
  /usr/bin/time -f "%e" -o "$work/time.txt" ./build/scallop run graphs/workpiece-contour.json --input cloud="$cloud" \
    --set smooth=0 --set denoise=none --set exact_edges=true --set tool_radius="${R:-3}" \
    --set scallop_height="${H:-0.05}" --set chord_error="${E:-0.01}" --no-cache -o "$work/out-$n" -q \
    --events "$work/events-$n.jsonl" >/dev/null 2>"$work/stderr-$n.txt" || status=$?
  python3 - "$work/events-$n.jsonl" "$(tail -n 1 "$work/time.txt")" "$status" <<'PY'
import json, sys
events = [json.loads(line) for line in open(sys.argv[1])]
print(f'   {"node":<16} {"type":<22} {"seconds":>8} {"peak MiB":>9}')
programs_end = None
for e in events:
    if e["event"] == "node_finish":
        print(f'   {e["node"]:<16} {e["type"]:<22} {e["seconds"]:8.2f} {e.get("peak_mib", 0):9.0f}')
        if e["type"] == "post.setup_programs":
            programs_end = e["t"]
peak = max((e.get("peak_mib", 0) or 0) for e in events)
print(f'   programs written at {programs_end:.1f} s; whole run {float(sys.argv[2]):.1f} s '
      f'(exit {sys.argv[3]}: 3 is a failed certificate), peak {peak:.0f} MiB')
PY
done
