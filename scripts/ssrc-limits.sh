#!/bin/bash
# The screen-space cascades' limitations measured side by side with SPWI on the same frames
# (docs/QUALITY.md, "What the screen cannot hold"): a light behind the camera, an occluder hidden
# behind another, and a thin wall seen edge on. Each scene (160x120) is rendered by the path
# tracer (512 samples per pixel, kept in OUT under each scene's checksum), ssrc, ssrc --offscreen
# world, ssrc --merge fix and SPWI; prints each one's relative RMSE and writes
# OUT/limits_SCENE_METHOD.png (method, reference, error).
# Usage: scripts/ssrc-limits.sh [BUILD] [OUT]
set -euo pipefail
build=${1:-build}
out=${2:-$build/ssrc-limits}
bin=$build/bin/penumbra
mkdir -p "$out"
head='"penumbra": 1, "dimensions": 3,'
materials='"materials": {"grey": {"albedo": [0.5, 0.5, 0.5]}, "white": {"albedo": [0.7, 0.7, 0.7]},
  "lamp": {"albedo": [0, 0, 0], "emission": [40, 36, 30]}},'
floor='{"type": "disk", "center": [0, 0, 0], "normal": [0, 1, 0], "radius": 50, "material": "grey"}'
# A sphere light behind the camera, a block on the floor in view.
cat > "$out/offscreen.json" <<JSON
{$head $materials
 "camera": {"position": [0, 1.5, 3], "look_at": [0, 0.2, -1], "fov_y": 50, "width": 160, "height": 120},
 "objects": [$floor,
  {"type": "box", "center": [0, 0.3, -1], "size": [0.6, 0.6, 0.6], "material": "white"},
  {"type": "sphere", "center": [0.6, 1.2, 4.2], "radius": 0.3, "material": "lamp"}]}
JSON
# A post hidden from the camera behind a panel casts its shadow on the floor in view.
cat > "$out/hidden.json" <<JSON
{$head $materials
 "camera": {"position": [0, 1.2, 4], "look_at": [0, 0.3, 0], "fov_y": 50, "width": 160, "height": 120},
 "objects": [$floor,
  {"type": "box", "center": [-0.6, 0.6, 1.5], "size": [0.8, 1.2, 0.1], "material": "white"},
  {"type": "box", "center": [-0.6, 0.5, 0.4], "size": [0.15, 1.0, 0.15], "material": "white"},
  {"type": "sphere", "center": [-1.6, 1.0, 0.2], "radius": 0.25, "material": "lamp"}]}
JSON
# A wall 2 cm thick seen edge on splits the floor; the light is on its left, lower than its top:
# the floor on its right is dark.
cat > "$out/thin.json" <<JSON
{$head $materials
 "camera": {"position": [0, 1.5, 3], "look_at": [0, 0, -1], "fov_y": 50, "width": 160, "height": 120},
 "objects": [$floor,
  {"type": "box", "center": [0, 0.3, -1], "size": [0.02, 0.6, 4], "material": "white"},
  {"type": "sphere", "center": [-0.8, 0.3, -1], "radius": 0.15, "material": "lamp"}]}
JSON
for scene in offscreen hidden thin; do
  # The reference, kept under the scene's checksum (an edited scene gets a new one).
  ref=$out/ref_${scene}_$(cksum < "$out/$scene.json" | cut -d' ' -f1).pfm
  [ -f "$ref" ] || "$bin" render "$out/$scene.json" --method pt --spp 512 -o "$ref" -q
  line="$scene:"
  for method in ssrc ssrc_world ssrc_fix spwi; do
    case $method in
      ssrc_world) args=(--method ssrc --offscreen world) ;;
      ssrc_fix) args=(--method ssrc --merge fix) ;;
      *) args=(--method "$method") ;;
    esac
    img=$out/${scene}_$method.pfm
    "$bin" render "$out/$scene.json" "${args[@]}" -o "$img" -q
    e=$("$bin" compare "$img" "$ref" --radiance --json --montage "$out/limits_${scene}_$method.png" |
        python3 -c "import json, sys; print('%.3f' % json.load(sys.stdin)['relative_rmse'])")
    line="$line $method $e"
  done
  echo "$line"
done
