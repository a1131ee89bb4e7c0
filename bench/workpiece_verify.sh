#!/usr/bin/env bash
# The whole-workpiece measurement (issue 14): a CAD mesh through
# bench/mesh-workpiece-contour-uncertified.json (patches, contours, a program per clamping), then
# ../shared/tools/verify_part.py on the programs and setups.json it wrote.
#   bench/workpiece_verify.sh [MESH] [SCALE] [OUT]   (default: the fandisk x 50 into /tmp/scallop-workpiece)
set -euo pipefail
cd "$(dirname "$0")/.."
mesh=${1:-../shared/data/fandisk/fandisk.off}
scale=${2:-50}
out=${3:-/tmp/scallop-workpiece}
r=3 h=0.05 e=0.01
rm -rf "$out"
/usr/bin/time -f "scallop run: %e s, peak %M KB" ./build/scallop run bench/mesh-workpiece-contour-uncertified.json \
  --input mesh="$mesh" --set read.scale="$scale" --set tool_radius=$r --set scallop_height=$h --set chord_error=$e \
  -o "$out" --no-cache
/usr/bin/python3 ../shared/tools/verify_part.py --mesh "$mesh" --scale "$scale" --setups "$out/setups.json" \
  --tool-radius $r --scallop $h --chord $e --json "$out/verify_part.json" --plot "$out/verify_part.png" > "$out/verify_part.log"
/usr/bin/python3 - "$out/verify_part.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
keys = ["pass", "fail_reasons", "scallop_max", "scallop_p99", "scallop_max_interior", "frac_over_limit",
        "uncut_fraction", "gouge_max", "gouge_fraction", "rapids_through_part", "unreachable_fraction", "gcode_valid"]
print(json.dumps({k: r[k] for k in keys}, indent=1))
PY
