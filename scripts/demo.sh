#!/usr/bin/env bash
# `make demo`: install, build, render the built-in 2D scene and the 3D Cornell box, and say how
# long each stage took.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
JOBS=${JOBS:-$(nproc)}

now() { date +%s.%N; }
stage() {  # stage NAME COMMAND...
  local name=$1
  shift
  local t0
  t0=$(now)
  "$@" || return
  awk -v n="$name" -v a="$t0" -v b="$(now)" 'BEGIN { printf "demo: %-28s %7.1f s\n", n, b - a }'
}

stage "install dependencies" bash scripts/install-deps.sh
stage "configure (Release)" bash -c "cmake -S . -B '$BUILD' -DCMAKE_BUILD_TYPE=Release -DPENUMBRA_WERROR=${WERROR:-OFF} > '$BUILD.configure.log' 2>&1 || { cat '$BUILD.configure.log'; exit 1; }"
# The build's own percentage lines as it goes (a couple of minutes from scratch), the rest in the
# log, shown when the build fails. cmake's make runs as a top-level make (no directory lines).
echo "demo: building penumbra (the whole log: $BUILD.build.log)"
stage "build" bash -c "set -o pipefail; env -u MAKELEVEL -u MAKEFLAGS -u MFLAGS cmake --build '$BUILD' -j '$JOBS' --target penumbra_cli 2>&1 | tee '$BUILD.build.log' | { grep --line-buffered -E '^\[ *[0-9]+%\]' || true; } || { tail -n 40 '$BUILD.build.log'; exit 1; }"
mkdir -p out
echo "demo: rendering the built-in scene with radiance cascades:"
stage "render" "$BUILD/bin/penumbra" render -o out/demo.png -o out/demo.exr
echo "demo: the same scene with holographic radiance cascades:"
stage "render (hrc)" "$BUILD/bin/penumbra" render --method hrc -o out/demo_hrc.png -o out/demo_hrc.exr
echo "demo: HRC again on the GPU through Vulkan (Mesa's CPU driver where there is no GPU):"
if ! stage "render (hrc, gpu)" "$BUILD/bin/penumbra" render --method hrc --device gpu -o out/demo_hrc_gpu.png; then
  echo "demo: no Vulkan device here; the CPU renders above stand (docs/GPU.md)"
fi
echo "demo: a 3D scene: the Cornell box, path traced (4 bounces, 64 samples per pixel):"
stage "render (3D, pt)" "$BUILD/bin/penumbra" render scenes/3d/cornell.json --bounces 4 --spp 64 -o out/demo_cornell3d.png -o out/demo_cornell3d.exr
echo "demo: open out/demo.png (display) or out/demo.exr (linear fluence); out/demo_hrc.* for HRC;"
echo "demo: out/demo_cornell3d.png for the 3D Cornell box"
echo "demo: paint lights and walls in a window: $BUILD/bin/penumbra paint (docs/PAINTER.md)"
