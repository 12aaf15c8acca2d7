#!/usr/bin/env bash
# Where AQEM's time goes: perf record of one simplification of the 1M-triangle bumpy sphere of
# bench_aqem.py to 10% (one frame), reported per shared object, the heaviest symbols, and
# OpenMesh's named symbols. Needs Debian's linux-perf; file-static functions of the core appear
# as addresses in the extension.
set -euo pipefail
cd "$(dirname "$0")/.."
data=$(mktemp -d)
trap 'rm -rf "$data"' EXIT
perf record -q -F 999 -g -o "$data/perf.data" .venv/bin/python - <<'PY'
import sys
sys.path.insert(0, "bench")
from bench_aqem import bumpy_sphere
from animlod import simplify_animated
simplify_animated(bumpy_sphere(708, 708, 1), (0.1,), use_motion_features=False)
PY
perf report -i "$data/perf.data" --no-children -g none --sort dso --stdio 2>/dev/null | grep -E '^ +[0-9]' | head -n 5
perf report -i "$data/perf.data" --no-children -g none --sort symbol --stdio 2>/dev/null | grep -E '^ +[0-9]' \
  > "$data/symbols.txt"
head -n 12 "$data/symbols.txt"
grep OpenMesh "$data/symbols.txt" \
  | awk 'NR <= 6 { print } { total += $1 } END { printf "OpenMesh connectivity, named symbols: %.1f%%\n", total }'
