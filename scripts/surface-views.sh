#!/bin/bash
# Surface radiance cascades baked once (`penumbra bake`) and viewed from the scene's camera and
# from two cameras moved around it (`render --method surface --atlas`), each against the path
# tracer from the same camera (512 samples per pixel at 160x120, made once in BUILD/surface-views).
# Prints per scene the bake's seconds and, per camera, the relative RMSE and the view's seconds.
# Usage: scripts/surface-views.sh [BUILD] [bake options...]
set -euo pipefail
build=${1:-build}
shift || true
bin=$build/bin/penumbra
dir=$build/surface-views
mkdir -p "$dir"
[ -f "$build/ssrc-quality/sphere.json" ] || bash scripts/ssrc-quality.sh "$build" >/dev/null
# scene | camera 1 (position, look_at) | camera 2
cases=(
  "$build/ssrc-quality/sphere.json|4 2 -3|0 0.3 0|-2 0.8 1.5|1 0 -1"
  "$build/ssrc-quality/skysphere.json|-3 1.5 -3|0 0.5 0|0.5 5 0.5|0 0 0"
  "scenes/3d/cornell.json|100 100 300|400 300 500|450 450 -200|200 100 400"
  "scenes/3d/offscreen.json|3 2 -2|0 0.5 0|-2 0.6 2|0.8 0.4 -0.3"
)
for c in "${cases[@]}"; do
  IFS='|' read -r scene p1 l1 p2 l2 <<<"$c"
  name=$(basename "$scene" .json)
  start=$(date +%s.%N)
  "$bin" bake "$scene" -o "$dir/$name.exr" -q "$@"
  line="$name: bake $(printf %.1f "$(echo "$(date +%s.%N) - $start" | bc)") s;"
  for k in 0 1 2; do
    view=$dir/${name}_$k.json
    python3 - "$scene" "$view" "$k" "$p1" "$l1" "$p2" "$l2" <<'PY'
import json, os, sys
scene, out, k = sys.argv[1], sys.argv[2], int(sys.argv[3])
d = json.load(open(scene))
base = os.path.dirname(os.path.abspath(scene))
# Relative paths in the document (meshes, textures) made absolute: the copy lives elsewhere.
def fix(v):
    if isinstance(v, dict):
        return {key: (base + '/' + x if key in ('file', 'path', 'texture') and isinstance(x, str)
                      and not x.startswith('/') else fix(x)) for key, x in v.items()}
    if isinstance(v, list):
        return [fix(x) for x in v]
    return v
d = fix(d)
if k > 0:
    p, l = sys.argv[2 + 2 * k].split(), sys.argv[3 + 2 * k].split()
    d['camera']['position'] = [float(x) for x in p]
    d['camera']['look_at'] = [float(x) for x in l]
    d['camera']['up'] = [0, 1, 0]
d['camera']['width'], d['camera']['height'] = 160, 120
json.dump(d, open(out, 'w'))
PY
    ref=$dir/ref_${name}_$k.pfm
    [ -f "$ref" ] || "$bin" render "$view" --method pt --spp 512 -o "$ref" -q
    # The bake's hash leaves the camera out: the view's scene is the baked one.
    start=$(date +%s.%N)
    "$bin" render "$view" --method surface --atlas "$dir/$name.exr" -o "$dir/view_${name}_$k.pfm" \
      -o "$dir/view_${name}_$k.png" -q
    secs=$(echo "$(date +%s.%N) - $start" | bc)
    e=$("$bin" compare "$dir/view_${name}_$k.pfm" "$ref" --radiance --json |
        python3 -c "import json, sys; print('%.3f' % json.load(sys.stdin)['relative_rmse'])")
    line="$line camera $k $e ($(printf %.2f "$secs") s)"
  done
  echo "$line"
done
