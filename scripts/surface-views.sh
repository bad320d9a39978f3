#!/bin/bash
# Surface radiance cascades baked once (`penumbra bake`) and viewed from the scene's camera and
# from two cameras moved around it (`render --method surface --atlas`), each against the path
# tracer from the same camera (512 samples per pixel at 160x120, made once in BUILD/surface-views).
# Prints per scene the bake's seconds and, per camera, the relative RMSE over every pixel, over the
# surfaces' pixels (emitters and the pixel around their silhouettes left out: one sample per
# pixel against the reference's 512 spread over the pixel makes their edges differ by the whole
# emission, whatever the light), and the view's seconds.
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
  "scenes/3d/offscreen.json|2.5 2.2 1|-0.5 0.3 -0.5|-2 0.6 2|0.8 0.4 -0.3"
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
    # Keyed by the view's document, so a camera changed here is traced again.
    ref=$dir/ref_${name}_${k}_$(md5sum <"$view" | cut -c1-8).pfm
    [ -f "$ref" ] || "$bin" render "$view" --method pt --spp 512 -o "$ref" -q
    # The bake's hash leaves the camera out: the view's scene is the baked one.
    start=$(date +%s.%N)
    "$bin" render "$view" --method surface --atlas "$dir/$name.exr" -o "$dir/view_${name}_$k.pfm" \
      -o "$dir/view_${name}_$k.png" -q
    secs=$(echo "$(date +%s.%N) - $start" | bc)
    e=$("$bin" compare "$dir/view_${name}_$k.pfm" "$ref" --radiance --json |
        python3 -c "import json, sys; print('%.3f' % json.load(sys.stdin)['relative_rmse'])")
    "$bin" render "$view" --aov emission -o "$dir/emission_${name}_$k.pfm" -q
    s=$(python3 - "$dir/view_${name}_$k.pfm" "$ref" "$dir/emission_${name}_$k.pfm" <<'PY'
import math, struct, sys
def pfm(path):
    with open(path, 'rb') as f:
        kind = f.readline().strip()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        n = w * h * (3 if kind == b'PF' else 1)
        v = struct.unpack(('<' if scale < 0 else '>') + 'f' * n, f.read(4 * n))
    return w, h, v
w, h, test = pfm(sys.argv[1])
_, _, ref = pfm(sys.argv[2])
_, _, emit = pfm(sys.argv[3])
lit = [max(emit[3 * i:3 * i + 3]) > 0 for i in range(w * h)]
sq = total = 0.0
n = 0
for y in range(h):
    for x in range(w):
        if any(lit[yy * w + xx] for yy in range(max(0, y - 1), min(h, y + 2))
               for xx in range(max(0, x - 1), min(w, x + 2))):
            continue
        i = 3 * (y * w + x)
        for c in range(3):
            sq += (test[i + c] - ref[i + c]) ** 2
            total += ref[i + c]
        n += 3
print('%.3f' % (math.sqrt(sq / n) / (total / n)))
PY
)
    line="$line camera $k $e / $s ($(printf %.2f "$secs") s)"
  done
  echo "$line"
done
