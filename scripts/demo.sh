#!/usr/bin/env bash
# The main job: install what is missing, build, and run the shipped graph on the bundled example.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
./build/scallop run graphs/isoparametric-zigzag.json -o out/example --no-cache
echo "outputs in out/example/: gcode.ngc (G-code), report.json (certificate), preview.png, scallop_map.png"
# The certificate's verdict in one line (report.json: pass, scallop_max_interior, gouge_max, in mm).
verdict=$(tr -d ' \n' < out/example/report.json |
  grep -o '"gouge_max":[^,}]*\|"pass":[a-z]*\|"scallop_max_interior":[^,}]*' | tr '\n' ' ')
echo "certificate: ${verdict}"
