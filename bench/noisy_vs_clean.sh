#!/usr/bin/env bash
# Noisy against clean (issue 15: a noisy cloud takes no more than 2 times its clean cloud): each
# catalog surface's 50 000-point cloud, clean and with sigma = 0.02 mm of noise (seed 1), through
# the zig-zag graph without the cache at h = 0.1 (where such noisy clouds are planned; r = 4, the
# bowl 2; e = 0.01). Prints the whole run's wall time, the four slowest nodes' and the ratio.
#   bench/noisy_vs_clean.sh [SURFACE ...]      default: the seven catalog surfaces
#   GRAPH=graphs/isoparametric-contour.json BENCH_DIR=/tmp/nvc bench/noisy_vs_clean.sh plane
set -euo pipefail
cd "$(dirname "$0")/.."
graph=${GRAPH:-graphs/isoparametric-zigzag.json}
tools=${SCALLOP_TOOLS:-../shared/tools}
work=${BENCH_DIR:-/tmp/scallop-noisy-vs-clean}
surfaces=("$@")
[ ${#surfaces[@]} -gt 0 ] || surfaces=(plane dome bowl saddle waves freeform canopy)
mkdir -p "$work"
for s in "${surfaces[@]}"; do
  r=4
  [ "$s" = bowl ] && r=2
  clean_s=
  for noise in 0 0.02; do
    cloud="$work/${s}_${noise}.ply"
    if [ ! -f "$cloud" ]; then
      extra=()
      [ "$noise" = 0 ] || extra=(--noise "$noise")
      /usr/bin/python3 "$tools/make_cloud.py" --surface "$s" --n 50000 --seed 1 "${extra[@]}" -o "$cloud"
    fi
    out="$work/${s}_${noise}"
    rm -rf "$out"
    start=$(date +%s.%N)
    status=0
    ./build/scallop run "$graph" --input cloud="$cloud" --set tool_radius=$r --set scallop_height=0.1 \
      --set chord_error=0.01 --no-cache -q -o "$out" --events "$out.events" >/dev/null 2>&1 || status=$?
    end=$(date +%s.%N)
    seconds=$(/usr/bin/python3 -c "print(round($end - $start, 2))")
    /usr/bin/python3 - "$s" "$noise" "$seconds" "$status" "$out" "${clean_s:-0}" <<'EOF'
import json, os, sys
surface, noise, seconds, status, out, clean = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4], sys.argv[5], float(sys.argv[6])
nodes = {}
for line in open(out + ".events"):
    ev = json.loads(line)
    if ev.get("event") == "node_finish":
        nodes[ev["node"]] = ev["seconds"]
slowest = sorted(nodes.items(), key=lambda kv: -kv[1])[:4]
report = os.path.join(out, "report.json")
verdict = json.load(open(report)).get("pass") if os.path.exists(report) else "no report (exit %s)" % status
ratio = " (%.2fx the clean cloud)" % (seconds / clean) if clean > 0 else ""
print("%-9s sigma %-4s %6.1f s%s  %s  certificate pass %s" % (
    surface, noise, seconds, ratio, " ".join("%s %.2f" % kv for kv in slowest), verdict))
EOF
    [ "$noise" = 0 ] && clean_s=$seconds
  done
done
