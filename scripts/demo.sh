#!/usr/bin/env bash
# The main job: install what is missing, build, and run the shipped graph on the bundled example.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
./build/scallop run graphs/prepare-cloud.json -o out/example --no-cache
