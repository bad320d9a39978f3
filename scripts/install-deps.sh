#!/usr/bin/env bash
# Installs the Debian packages Penumbra needs to build, test, fuzz and benchmark (clang-14 and
# libclang-rt-14-dev, which holds libclang_rt.fuzzer, for scripts/fuzz.sh; glmark2-data's bunny
# and assimp-testmodels' glTF files for the 3D example scenes and tests).
# Idempotent and quiet: does nothing when everything is already there.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libtbb-dev libstb-dev libopenexr-dev nlohmann-json3-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libpng-dev
  libglfw3-dev libgl-dev libglx-mesa0 libgl1-mesa-dri libimgui-dev xvfb xdotool
  libvulkan-dev glslc mesa-vulkan-drivers
  libembree-dev libtinyobjloader-dev libtinygltf-dev
  glmark2-data assimp-testmodels
  clang-14 libclang-rt-14-dev
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install-deps: installing ${missing[*]}"
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
