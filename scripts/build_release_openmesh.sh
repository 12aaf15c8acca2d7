#!/usr/bin/env bash
# Builds a release (NDEBUG) OpenMesh from Debian's own source package into a git-ignored
# prefix of the checkout. Debian's libopenmesh-dev is compiled with assertions on, which makes
# edge collapses 5-7x slower (third_party_notes.md has the timings).
#
# The deb-src entry is derived at run time from the machine's own apt sources and lives in a
# private apt directory, so the system's apt configuration is never touched and no package
# host is written into the repository.
#
# usage: scripts/build_release_openmesh.sh PREFIX     (a second run with PREFIX present is a no-op)
set -euo pipefail

prefix=$(realpath -m "${1:?usage: $0 PREFIX}")
if [ -f "$prefix/lib/cmake/OpenMesh/OpenMeshConfig.cmake" ]; then
  echo "release OpenMesh already in $prefix"
  exit 0
fi

work=$(realpath -m "$prefix/../openmesh-src")
apt_dir="$work/apt"
rm -rf "$work"
mkdir -p "$apt_dir/lists/partial" "$apt_dir/sources.list.d" "$apt_dir/archives/partial"

# Derive deb-src entries from the machine's own sources (deb822 and one-line formats).
shopt -s nullglob
for f in /etc/apt/sources.list.d/*.sources; do
  sed -e 's/^Types:.*/Types: deb-src/' "$f" > "$apt_dir/sources.list.d/$(basename "$f")"
done
for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
  [ -f "$f" ] && grep -E '^deb ' "$f" | sed -e 's/^deb /deb-src /' >> "$apt_dir/sources.list.d/derived.list" || true
done

apt_opts=(-o "Dir::Etc::SourceList=/dev/null"
          -o "Dir::Etc::SourceParts=$apt_dir/sources.list.d"
          -o "Dir::State::Lists=$apt_dir/lists"
          -o "Dir::Cache::Archives=$apt_dir/archives"
          -o "APT::Sandbox::User=root")
apt-get "${apt_opts[@]}" update -qq
(cd "$work" && apt-get "${apt_opts[@]}" source --only-source --download-only openmesh)
dsc=$(ls "$work"/openmesh_*.dsc | head -n 1)
(cd "$work" && dpkg-source --no-check -x "$dsc" src > /dev/null)

# OpenMesh's CMake builds shared libraries on every platform but Windows; build static ones
# (PIC) instead, so that the core and the Python extension carry no run-time OpenMesh dependency.
sed -i -E 's/vci_add_library \((OpenMesh(Core|Tools)) SHARED/vci_add_library (\1 STATIC/' \
  "$work/src/src/OpenMesh/Core/CMakeLists.txt" "$work/src/src/OpenMesh/Tools/CMakeLists.txt"

# OpenMesh 9.0 asks for CMake 3.3, which CMake 4 refuses without the policy floor.
cmake -S "$work/src" -B "$work/build" -G Ninja \
  -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  -DCMAKE_POSITION_INDEPENDENT_CODE=ON \
  -DBUILD_APPS=OFF \
  -DOPENMESH_DOCS=OFF \
  -DCMAKE_INSTALL_PREFIX="$prefix" > "$work/configure.log"
cmake --build "$work/build" --parallel "$(nproc)"
cmake --install "$work/build" > /dev/null
rm -rf "$work"
echo "release OpenMesh installed in $prefix"
