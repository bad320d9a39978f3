#!/bin/bash
# The direct radiance field renderer (`penumbra field`) against the path tracer from the same
# cameras: a small scene behind a window (the Cornell box through its open front) and a volume
# (the fog shaft, the window inside the room), at three probe densities. Per run: the bake's
# seconds and memory, and per view (the scene's camera, then turned +15 and -15 degrees about
# the window) the relative RMSE over the window's pixels, then over those that see no emitter
# within a pixel, and the view's milliseconds; a montage (field, path tracer, error) of view 1.
# Usage: scripts/field-quality.sh [BUILD] [field options...]
set -euo pipefail
build=${1:-build}
shift || true
bin=$build/bin/penumbra
dir=$build/field-quality
mkdir -p "$dir"
# scene | window (corner, u, v) | spp | reference spp | bounces
cases=(
  "scenes/3d/cornell.json|0,0,-1,556,0,0,0,548,0|32|256|2"
  "scenes/3d/fog_shaft.json|-1,0.05,1.9,0,0,-3.8,0,2.9,0|64|256|2"
)
echo "| scene | texels | probes | cascades | bake s | memory MiB | view 0 | view 1 | view 2 | away from emitters | view ms |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for c in "${cases[@]}"; do
  IFS='|' read -r scene window spp ref bounces <<<"$c"
  name=$(basename "$scene" .json)
  for texels in 32 64 128; do
    "$bin" field "$scene" --window="$window" --texels "$texels" --spp "$spp" --bounces "$bounces" \
      --views 3 --reference "$ref" -o "$dir/${name}_$texels.pfm" --json "$@" \
      >"$dir/${name}_$texels.json"
    # The field, the path tracer and their difference side by side, from the turned camera.
    "$bin" compare "$dir/${name}_$texels.view1.pfm" "$dir/${name}_$texels.view1.reference.pfm" \
      --radiance --montage "$dir/${name}_${texels}_view1_montage.png" -q
    python3 - "$dir/${name}_$texels.json" "$name" "$texels" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
v = j["views"]
print("| %s | %s | %dx%d | %d | %.1f | %.1f | %s | %s | %.1f |" % (
    sys.argv[2], sys.argv[3], j["probes_u"], j["probes_v"], j["parameters"]["cascades"],
    j["bake_ms"] / 1000, j["memory_bytes"] / 2**20,
    " | ".join("%.3f" % x["relative_rmse"] for x in v),
    " / ".join("%.3f" % x["relative_rmse_without_emitters"] for x in v),
    sum(x["time_ms"] for x in v) / len(v)))
PY
  done
done
