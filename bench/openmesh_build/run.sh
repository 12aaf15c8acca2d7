#!/usr/bin/env bash
# Builds OpenMesh's Decimater benchmark against the release OpenMesh (.deps/openmesh) and
# against Debian's libopenmesh-dev, and prints one row each: why animlod builds its own.
set -euo pipefail
cd "$(dirname "$0")/../.."
echo
echo "### OpenMesh Decimater (ModQuadric), 200k -> 20k faces: release build vs Debian package"
echo
echo "| OpenMesh | faces before | faces after | seconds |"
echo "|---|---|---|---|"
for build in release debian; do
  if [ "$build" = release ]; then config=$PWD/.deps/openmesh/lib/cmake/OpenMesh
  else config=$(dirname "$(dpkg -L libopenmesh-dev | grep '/OpenMeshConfig.cmake$' | head -n 1)"); fi
  cmake -S bench/openmesh_build -B "build/openmesh_bench_$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DOpenMesh_DIR="$config" > /dev/null
  cmake --build "build/openmesh_bench_$build" > /dev/null
  "build/openmesh_bench_$build/openmesh_decimater_bench" "$build ($config)"
done
