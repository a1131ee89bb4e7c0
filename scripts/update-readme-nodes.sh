#!/usr/bin/env bash
# Regenerates the node reference in README.md from the declarations (scallop nodes --markdown).
set -euo pipefail
cd "$(dirname "$0")/.."
ref=$(./build/scallop nodes --markdown)
/usr/bin/python3 - "$ref" <<'PY'
import re, sys
text = open("README.md").read()
begin, end = "<!-- nodes:begin -->", "<!-- nodes:end -->"
head, rest = text.split(begin)
_, tail = rest.split(end)
open("README.md", "w").write(head + begin + "\n" + sys.argv[1] + "\n" + end + tail)
PY
