#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, docs/RELIABILITY.md) with clang in build-fuzz and runs
# each for N seconds (default 60). A crash, a sanitizer report, a leak, an input slower than
# the timeout or memory over the limit fails the script; the input is kept under
# <build>/fuzz-work/artifacts/ (re-run it with: <build>/bin/<target> <file>).
#   scripts/fuzz.sh [seconds per target]
# Environment: FUZZ_BUILD (build-fuzz), JOBS (nproc), WERROR (OFF), FUZZ_TARGETS (all six).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
seconds=${1:-60}
build=${FUZZ_BUILD:-build-fuzz}
jobs=${JOBS:-$(nproc)}
targets=(${FUZZ_TARGETS:-fuzz_scene fuzz_image fuzz_strokes fuzz_scene3d fuzz_mesh fuzz_atlas})

if ! command -v clang++-14 >/dev/null; then
  echo "fuzz.sh: clang++-14 is missing (scripts/install-deps.sh installs it)" >&2
  exit 1
fi
start=$SECONDS
CC=clang-14 CXX=clang++-14 cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release \
  -DPENUMBRA_FUZZ=ON -DPENUMBRA_BUILD_TESTS=OFF -DPENUMBRA_BUILD_BENCH=OFF \
  -DPENUMBRA_WERROR="${WERROR:-OFF}" >"$build.configure.log" 2>&1 ||
  { cat "$build.configure.log"; exit 1; }
# Only the fuzzers and the seed writer: the command line and the tools are not needed here.
# cmake's make as a top-level make: no "Entering directory" lines under `make fuzz`.
env -u MAKELEVEL -u MAKEFLAGS -u MFLAGS cmake --build "$build" -j "$jobs" --target "${targets[@]}" penumbra_fuzz_seeds
echo "== fuzz.sh: build took $((SECONDS - start)) s"
start=$SECONDS

# Seeds, made afresh each run from files already in the repository and generated images.
work=$root/$build/fuzz-work
rm -rf "$work/seeds" "$work/layers"
mkdir -p "$work/seeds/scene" "$work/seeds/strokes" "$work/artifacts"
"$root/$build/bin/penumbra_fuzz_seeds" "$work/gen"
cp "$root"/scenes/*.json "$work/gen/scene/"* "$work/seeds/scene/"
cp "$root"/scenes/strokes/*.json "$work/seeds/strokes/"
printf '%s' '{"size": [16, 8], "strokes": [{"tool": "erase", "radius": 1, "points": [[1, 1]]}]}' \
  >"$work/seeds/strokes/erase.json"
# Layer paths in the seed scenes are relative to the fuzzer's working directory, $work: the
# examples' layers and the tiny generated ones.
mkdir -p "$work/layers"
cp "$root"/scenes/layers/* "$work/gen/layers/"* "$work/layers/"
rm -rf "$work/seeds/image" "$work/seeds/atlas"
cp -r "$work/gen/image" "$work/seeds/image"
# Atlases baked for fuzz/atlas_scene.hpp's scene, with and without the radiance per direction.
cp -r "$work/gen/atlas" "$work/seeds/atlas"
# 3D: the example scenes (their meshes are Debian's, by absolute path), and mesh files behind
# the byte that picks their format (0 .obj, 1 .gltf, 2 .glb).
rm -rf "$work/seeds/scene3d" "$work/seeds/mesh"
mkdir -p "$work/seeds/scene3d" "$work/seeds/mesh"
cp "$root"/scenes/3d/*.json "$work/seeds/scene3d/"
models=/usr/share/assimp/models/glTF2
seed_mesh() {  # seed_mesh FORMAT_BYTE FILE NAME
  { printf "\\$(printf '%03o' "$1")"; cat "$2"; } >"$work/seeds/mesh/$3"
}
seed_mesh 1 "$models/BoxTextured-glTF-Embedded/BoxTextured.gltf" box-embedded.gltf
seed_mesh 2 "$models/BoxTextured-glTF-Binary/BoxTextured.glb" box.glb
printf '\000v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nvt 0 0\nf 1/1/1 2/1/1 4/1/1 3/1/1\n' \
  >"$work/seeds/mesh/quad.obj"
# Hard inputs (issue 37, docs/RELIABILITY.md "3D"): a face of 300 corners (past tinyobjloader's
# byte count), a comb of 40 (ear clipping); scenes at the world's bound, too bright or of 3e37
# sky, with a camera whose up is 1e-30 long.
awk 'BEGIN { printf "%c", 0; for (i = 0; i < 300; i++) printf "v %f %f 0\n", cos(i / 47.75), sin(i / 47.75);
  printf "f"; for (i = 1; i <= 300; i++) printf " %d", i; printf "\n" }' >"$work/seeds/mesh/ngon.obj"
awk 'BEGIN { printf "%c", 0; for (i = 0; i < 20; i++) printf "v %d 0 0\nv %d 3 0\n", 2 * i, 2 * i + 1;
  printf "v 40 -1 0\nv 0 -1 0\nf"; for (i = 1; i <= 42; i++) printf " %d", i; printf "\n" }' \
  >"$work/seeds/mesh/comb.obj"
hard='"penumbra": 1, "dimensions": 3, "camera": {"position": [0, 1, 4], "look_at": [0, 0, 0],
  "fov_y": 50, "width": 8, "height": 6'
echo "{$hard, \"up\": [0, 1e-30, 0]}, \"sky\": [3e37, 3e37, 3e37], \"objects\": [
  {\"type\": \"disk\", \"center\": [0, 0, 0], \"normal\": [0, 1, 0], \"radius\": 5},
  {\"type\": \"sphere\", \"center\": [9e14, 0, 0], \"radius\": 1}]}" >"$work/seeds/scene3d/edge.json"
echo "{$hard}, \"materials\": {\"w\": {\"albedo\": [1, 1, 1], \"emission\": [1e38, 1e38, 1e38]}},
  \"objects\": [{\"type\": \"box\", \"center\": [0, 0, 0], \"size\": [20, 20, 20],
  \"material\": \"w\"}]}" >"$work/seeds/scene3d/bright.json"

# The targets run side by side, $jobs at a time (each libFuzzer process uses one core); their
# summaries are printed in order once all have ended.
run_target() {  # run_target TARGET: its log in $work/TARGET.log, its status in $work/TARGET.status
  local t=$1 kind=${1#fuzz_}
  local corpus=$work/corpus/$kind
  mkdir -p "$corpus"
  # Inputs up to 16 KiB: the largest example scene (124 KB) only slows each run, and an image
  # needs room for a header and an EXR's offset table (1024 entries for 16384 lines).
  local status=0
  (cd "$work" && "$root/$build/bin/$t" "$corpus" "$work/seeds/$kind" \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=16384 \
    -artifact_prefix="$work/artifacts/$t-" -print_final_stats=1 \
    >"$work/$t.log" 2>&1) || status=$?
  echo "$status" >"$work/$t.status"
}
echo "== fuzz.sh: ${targets[*]} for ${seconds}s each, $jobs at a time"
running=0
for t in "${targets[@]}"; do
  rm -f "$work/$t.status"
  if ((running >= jobs)); then
    wait -n || true
    running=$((running - 1))
  fi
  run_target "$t" &
  running=$((running + 1))
done
wait
failed=()
for t in "${targets[@]}"; do
  echo "== fuzz.sh: $t"
  if [[ $(cat "$work/$t.status" 2>/dev/null) == 0 ]]; then
    grep -E '^#[0-9]+.*(DONE|pulse)' "$work/$t.log" | tail -1 || true
    grep -E '^stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)' "$work/$t.log" || true
  else
    tail -n 60 "$work/$t.log"
    echo "== fuzz.sh: $t FAILED (log: $work/$t.log, input under $work/artifacts/)"
    failed+=("$t")
  fi
done
echo "== fuzz.sh: runs took $((SECONDS - start)) s"
echo "fuzz: $((${#targets[@]} - ${#failed[@]})) passed, ${#failed[@]} failed"
[ ${#failed[@]} -eq 0 ] || { echo "fuzz.sh: failed: ${failed[*]}"; exit 1; }
