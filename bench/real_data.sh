#!/usr/bin/env bash
# Runs the three shipped patch graphs (zig-zag, contour, raster) on the real clouds of ../shared/data and prints, per run, the
# certificate (post.simulate) or the error that stopped it. The hemisphere's programs are then
# judged by verify.py (SCALLOP_TOOLS, default ../shared/tools) against its true surface, the
# sphere of radius 50 up to the trim's 75 degrees (bench/sphere_cap_mesh.py).
set -uo pipefail
cd "$(dirname "$0")/.."
data=${SCALLOP_DATA:-../shared/data}
work=${BENCH_DIR:-/tmp/scallop-real}
mkdir -p "$work"
runs=("hemisphere hemisphere/hemisphere.off 50" "cturtle cturtle/cturtle.pcd 50" "camelhead camelhead/camelhead.off 500"
      "bunny_scan bunny_scan/bun000.ply 500" "milk_kinect milk_kinect/milk.pcd 500")
for run in "${runs[@]}"; do
  read -r name file scale <<<"$run"
  for labelled in zigzag:isoparametric-zigzag contour:isoparametric-contour raster:raster-zigzag; do
    graph=${labelled%%:*}
    out="$work/${name}_$graph"
    rm -rf "$out"
    err=$(./build/scallop run "graphs/${labelled#*:}.json" --input cloud="$data/$file" --set read.scale="$scale" \
      --no-cache -q -o "$out" 2>&1 >/dev/null | grep '^error:' | head -1)
    if [ -f "$out/report.json" ]; then
      /usr/bin/python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print(f\"| $name (x$scale) | $graph | path | {r['scallop_max_interior']:.4f} | {r['gouge_max']:.4f} | {r['uncut_fraction']:.4f} | {r['pass']} |\")" "$out/report.json"
    else
      echo "| $name (x$scale) | $graph | ${err#error: } |||||"
    fi
  done
done
tools=${SCALLOP_TOOLS:-../shared/tools}
cap="$work/sphere_cap75.ply"
[ -f "$cap" ] || /usr/bin/python3 bench/sphere_cap_mesh.py -o "$cap" --radius 50 --max-angle 75 >/dev/null
for graph in zigzag contour raster; do
  gcode="$work/hemisphere_$graph/gcode.ngc"
  [ -f "$gcode" ] || continue
  /usr/bin/python3 "$tools/verify.py" --gcode "$gcode" --tool-radius 4 --scallop 0.05 --chord 0.01 --mesh "$cap" \
    --json "$work/hemisphere_$graph.verify.json" >/dev/null
  /usr/bin/python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print(f\"| hemisphere (x50), true sphere | $graph | verify.py | whole {r['scallop_max']:.4f}, interior {r['scallop_max_interior']:.4f} | {r['gouge_max']:.4f} | {r['uncut_fraction']:.4f} | {r['pass']} |\")" "$work/hemisphere_$graph.verify.json"
done
