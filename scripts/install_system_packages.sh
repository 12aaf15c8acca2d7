#!/usr/bin/env bash
# Installs the Debian packages animlod needs (DESIGN.md's list, plus the Python headers and
# venv for building the extension, doctest for the C++ tests, dpkg-dev for unpacking the
# OpenMesh source package, libnlopt-dev for the core's motion LoD SLSQP, libstb-dev for the
# crowd benchmark's PNG screenshots, nlohmann-json3-dev for its KHR_animation_pointer channels,
# assimp-testmodels, assimp-utils, gltfpack and castle-game-engine-doc, whose examples are
# Blender-exported characters, for the tests on other tools' files). Installs
# only what is missing, so a second run is quick.
# Extra package names given as arguments are installed too (`make fuzz` adds clang's).
set -euo pipefail

packages=(g++ cmake ninja-build pkg-config libopenmesh-dev libeigen3-dev libglm-dev libglfw3-dev
          libgl-dev libegl-dev libopengl-dev libtinygltf-dev xvfb xauth libgl1-mesa-dri libegl-mesa0
          doctest-dev dpkg-dev python3-dev python3-venv libstb-dev libnlopt-dev nlohmann-json3-dev
          assimp-testmodels assimp-utils gltfpack castle-game-engine-doc)
packages+=("$@")

missing=()
for package in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$package" 2>/dev/null || true)
  [ "$status" = "install ok installed" ] || missing+=("$package")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "system packages: all present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "system packages: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" > /dev/null
