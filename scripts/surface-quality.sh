#!/bin/bash
# Surface radiance cascades (--method surface) against the path tracer on the screen-space
# scenes of scripts/ssrc-quality.sh (whose references, 512 samples per pixel at 160x120, it makes
# or reuses in BUILD/ssrc-quality) and the example scenes with lights off screen (two rooms, a
# light behind the camera). Prints each scene's relative RMSE and the render's seconds.
# Usage: scripts/surface-quality.sh [BUILD] [surface options...]
set -euo pipefail
build=${1:-build}
shift || true
bin=$build/bin/penumbra
dir=$build/ssrc-quality
[ -f "$dir/sphere.json" ] || bash scripts/ssrc-quality.sh "$build" >/dev/null
line="$*:"
for scene in "$dir/sphere.json" "$dir/skysphere.json" scenes/3d/cornell.json \
             scenes/3d/bunny_sky.json scenes/3d/four_cubes.json scenes/3d/two_rooms.json \
             scenes/3d/offscreen.json; do
  name=$(basename "$scene" .json)
  ref=$dir/ref_$name.pfm
  [ -f "$ref" ] || "$bin" render "$scene" --method pt --spp 512 --width 160 --height 120 -o "$ref" -q
  start=$(date +%s.%N)
  "$bin" render "$scene" --method surface --width 160 --height 120 -o "$dir/surface_$name.pfm" \
    -q "$@"
  secs=$(echo "$(date +%s.%N) - $start" | bc)
  crops=("")
  [ "$name" = sphere ] && crops=("--crop 0 0 160 45" "--crop 0 75 160 45")
  for crop in "${crops[@]}"; do
    # shellcheck disable=SC2086
    e=$("$bin" compare "$dir/surface_$name.pfm" "$ref" --radiance --json $crop |
        python3 -c "import json, sys; print('%.3f' % json.load(sys.stdin)['relative_rmse'])")
    line="$line $name $e"
  done
  line="$line (${secs%???????} s)"
done
echo "$line"
