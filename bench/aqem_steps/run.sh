#!/usr/bin/env bash
# The AQEM speed steps of issue 8, measured in one run: every commit given (default: the steps
# in README's AQEM speed table) is exported with git archive, its core library built (Release,
# -j2), and aqem_time.cpp linked against it; then the meshes of bench_aqem.py's speed table are
# simplified to 10% by each step in turn (best of REPEATS), beside fast-simplification and
# meshoptimizer, with the load average. Prints a Markdown table. Run from the repository root:
#   bench/aqem_steps/run.sh [COMMIT...]
set -euo pipefail
cd "$(dirname "$0")/../.."
root=$(pwd)
work=${AQEM_STEPS_DIR:-build/aqem_steps}
repeats=${REPEATS:-3}
commits=("$@")
if [ ${#commits[@]} -eq 0 ]; then commits=(e69870e 2c73fc8 61481a6 cb29ea0); fi
mkdir -p "$work"
openmesh=$(readlink -f .deps/openmesh)
# One source tree and build directory, moved from step to step: only the files a step changed
# are rewritten (fresh timestamps), so ninja rebuilds just those.
source_dir="$work/src"
previous=""
for commit in "${commits[@]}"; do
  sha=$(git rev-parse --short "$commit")
  if [ -z "$previous" ]; then
    if [ ! -d "$source_dir/build" ]; then
      mkdir -p "$source_dir"
      git archive "$sha" | tar -x -C "$source_dir"
      ln -sfn "$(dirname "$openmesh")" "$source_dir/.deps"
      cmake -S "$source_dir" -B "$source_dir/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DANIMLOD_BUILD_TESTS=OFF \
        -DANIMLOD_BUILD_CROWD=OFF -DANIMLOD_INSTALL=OFF > "$work/configure.log"
    fi
    git diff --name-only "$(cat "$work/at" 2>/dev/null || echo "$sha")" "$sha" -- cpp > "$work/changed"
  else
    git diff --name-only "$previous" "$sha" -- cpp > "$work/changed"
  fi
  while read -r file; do
    if git cat-file -e "$sha:$file" 2>/dev/null; then mkdir -p "$source_dir/$(dirname "$file")"; git show "$sha:$file" > "$source_dir/$file"
    else rm -f "$source_dir/$file"; fi
  done < "$work/changed"
  echo "$sha" > "$work/at"
  cmake --build "$source_dir/build" --parallel 2 --target animlod_core > "$work/build_$sha.log"
  g++ -O3 -DNDEBUG -std=c++17 -I"$source_dir/cpp/include" bench/aqem_steps/aqem_time.cpp \
    "$source_dir/build/cpp/libanimlod_core.a" -L"$openmesh/lib" -Wl,-Bstatic -lOpenMeshCore -Wl,-Bdynamic \
    -lnlopt -lpthread -o "$work/aqem_time_$sha"
  previous=$sha
done
.venv/bin/python - "$work" <<'PY'
import sys
sys.path.insert(0, "bench")
import numpy as np
from bench_aqem import bumpy_sphere, openmesh_bench_sphere
for name, mesh in (("1m", bumpy_sphere(710, 705, 1)), ("200k", openmesh_bench_sphere()), ("24f", bumpy_sphere(92, 92, 24))):
    with open(f"{sys.argv[1]}/{name}.bin", "wb") as f:
        np.array([mesh.frame_count, mesh.vertex_count, mesh.face_count], np.int64).tofile(f)
        mesh.frames.astype(np.float32).tofile(f)
        mesh.faces.astype(np.int32).tofile(f)
PY
echo "| step (commit) | 1M triangles, F = 1 | 200k triangles, F = 1 | 17k triangles, F = 24 | level error 1M | summed cost 1M | level hash 1M |"
echo "|---|---|---|---|---|---|---|"
for commit in "${commits[@]}"; do
  sha=$(git rev-parse --short "$commit")
  subject=$(git log -1 --format=%s "$sha" | cut -c1-70)
  IFS='|' read -r t1 _ e1 c1 h1 < <("$work/aqem_time_$sha" "$work/1m.bin" "$repeats")
  IFS='|' read -r t2 _ _ _ _ < <("$work/aqem_time_$sha" "$work/200k.bin" "$repeats")
  IFS='|' read -r t3 _ _ _ _ < <("$work/aqem_time_$sha" "$work/24f.bin" "$repeats")
  echo "| $subject ($sha) | $t1 s | $t2 s | $t3 s | $e1 | $c1 | $h1 |"
done
.venv/bin/python - "$work" <<'PY'
import sys, time
sys.path.insert(0, "bench")
import numpy as np
import fast_simplification
import meshoptimizer
from bench_aqem import bumpy_sphere, fast_simplification_replayed, openmesh_bench_sphere
cells = {}
for name, mesh in (("1m", bumpy_sphere(710, 705, 1)), ("200k", openmesh_bench_sphere())):
    target = mesh.face_count // 10
    indices = mesh.faces.ravel().astype(np.uint32)
    fs = mo = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        fast_simplification.simplify(mesh.frames[0], mesh.faces, target_count=target)
        fs = min(fs, time.perf_counter() - start)
        start = time.perf_counter()
        meshoptimizer.simplify(np.zeros_like(indices), indices, mesh.frames[0], target_index_count=3 * target, target_error=1.0)
        mo = min(mo, time.perf_counter() - start)
    cells[name] = (fs, mo)
mesh = bumpy_sphere(92, 92, 24)
replay = float("inf")
for _ in range(3):
    start = time.perf_counter()
    fast_simplification_replayed(mesh, 0.1)
    replay = min(replay, time.perf_counter() - start)
print(f"| fast-simplification (Python) | {cells['1m'][0]:.3f} s | {cells['200k'][0]:.3f} s | {replay:.3f} s (frame 0, replayed on every frame) | | | |")
print(f"| meshoptimizer simplify (Python) | {cells['1m'][1]:.3f} s | {cells['200k'][1]:.3f} s | | | | |")
PY
echo
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) cores"
