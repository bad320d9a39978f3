#!/bin/bash
# The screen-space cascades on the random scene family (docs/QUALITY.md, "Screen-space
# cascades"): two scenes of each class (behind: lights behind the camera; night: small lights;
# window: a room lit through a window) at 160x120, against the path tracer at 128 samples per
# pixel (kept in BUILD/ssrc-family). Prints each scene's relative RMSE.
# Usage: scripts/ssrc-family.sh [BUILD] [ssrc options...]
set -euo pipefail
build=${1:-build}
shift || true
bin=$build/bin/penumbra
dir=$build/ssrc-family
mkdir -p "$dir"
"$build/bin/penumbra_scene_family" "$dir" --count 2 > /dev/null
line="$*:"
for class in behind night window; do
  for k in 0 1; do
    scene=$dir/${class}_$k.json
    # The reference, kept under the scene's checksum (a changed family gets a new one).
    ref=$dir/ref_${class}_${k}_$(cksum < "$scene" | cut -d' ' -f1).pfm
    [ -f "$ref" ] || "$bin" render "$scene" --method pt --spp 128 -o "$ref" -q
    img=$dir/ssrc_${class}_$k.pfm
    "$bin" render "$scene" --method ssrc -o "$img" -q "$@"
    e=$("$bin" compare "$img" "$ref" --radiance --json |
        python3 -c "import json, sys; print('%.3f' % json.load(sys.stdin)['relative_rmse'])")
    line="$line ${class}_$k $e"
  done
done
echo "$line"
