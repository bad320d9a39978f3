#!/bin/bash
# The screen-space cascades against the path tracer on the scenes where everything that lights
# the picture is on screen (docs/QUALITY.md, "Screen-space cascades"): a sphere light over a floor
# seen from above (the floor behind the light and in front of it, the light's own pixels left
# out), sky over a black sphere, the Cornell box seen whole, the bunny under sky and sun, four
# cubes. Usage: scripts/ssrc-quality.sh [BUILD] [ssrc options...]; references (512 samples per
# pixel, 160x120) are kept in BUILD/ssrc-quality.
set -euo pipefail
build=${1:-build}
shift || true
bin=$build/bin/penumbra
dir=$build/ssrc-quality
mkdir -p "$dir"
cat > "$dir/sphere.json" <<'JSON'
{"penumbra": 1, "dimensions": 3,
 "camera": {"position": [0, 6, 3], "look_at": [0, 0, 0], "fov_y": 50, "width": 160, "height": 120},
 "materials": {"grey": {"albedo": [0.5, 0.5, 0.5]}, "light": {"emission": [8, 6, 4]}},
 "objects": [
  {"type": "disk", "center": [0, 0, 0], "normal": [0, 1, 0], "radius": 100, "material": "grey"},
  {"type": "sphere", "center": [0, 1, 0], "radius": 0.25, "material": "light"}]}
JSON
cat > "$dir/skysphere.json" <<'JSON'
{"penumbra": 1, "dimensions": 3,
 "camera": {"position": [0, 2.5, 4], "look_at": [0, 0.5, 0], "fov_y": 45, "width": 160, "height": 120},
 "sky": {"zenith": [0.6, 0.8, 1.2], "horizon": [1.0, 1.0, 1.0], "ground": [0.2, 0.2, 0.2]},
 "materials": {"grey": {"albedo": [0.6, 0.6, 0.6]}, "black": {"albedo": [0, 0, 0]}},
 "objects": [
  {"type": "disk", "center": [0, 0, 0], "normal": [0, 1, 0], "radius": 100, "material": "grey"},
  {"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6, "material": "black"}]}
JSON
line="$*:"
for scene in "$dir/sphere.json" "$dir/skysphere.json" scenes/3d/cornell.json \
             scenes/3d/bunny_sky.json scenes/3d/four_cubes.json; do
  name=$(basename "$scene" .json)
  ref=$dir/ref_$name.pfm
  [ -f "$ref" ] || "$bin" render "$scene" --method pt --spp 512 --width 160 --height 120 -o "$ref" -q
  "$bin" render "$scene" --method ssrc --width 160 --height 120 -o "$dir/ssrc_$name.pfm" -q "$@"
  crops=("")
  [ "$name" = sphere ] && crops=("--crop 0 0 160 45" "--crop 0 75 160 45")
  for crop in "${crops[@]}"; do
    # shellcheck disable=SC2086
    e=$("$bin" compare "$dir/ssrc_$name.pfm" "$ref" --radiance --json $crop |
        python3 -c "import json, sys; print('%.3f' % json.load(sys.stdin)['relative_rmse'])")
    line="$line $name $e"
  done
done
echo "$line"
