#!/usr/bin/env bash
# The glossy variants of the example scenes (scripts/glossy-scenes.py) rendered by a method and
# by the path tracer, and the relative RMSE between them (docs/QUALITY.md, "Glossy materials").
# Usage: scripts/glossy-quality.sh BUILD [METHOD] [OUT] [OPTION...]
#   BUILD   the build folder (its bin/penumbra)
#   METHOD  spwi (default)
#   OUT     where scenes, images and montages go (default BUILD/glossy-quality)
#   OPTION  passed on to the method's render (e.g. --specular wide); its images are named after
#           the method and the options (spwi.specular-wide.pfm)
# The sphere among small lights at 1 bounce against 512 samples per pixel; the bunny and the
# Cornell box at 2 bounces against 256 (their references keep some noise of their own); the
# floor under a gradient sky at 1 bounce against 256.
set -euo pipefail
build=${1:?usage: scripts/glossy-quality.sh BUILD [METHOD] [OUT] [OPTION...]}
method=${2:-spwi}
out=${3:-$build/glossy-quality}
shift $(($# < 3 ? $# : 3))
options=("$@")
tag=$method
for o in "${options[@]}"; do tag+=".${o#--}"; done
bin=$build/bin/penumbra
python3 "$(dirname "$0")/glossy-scenes.py" "$out"
run() {  # scene roughness bounces spp
  local s=$out/$1_r$2.json name=$1_r$2
  [ -f "$out/$name.pt.pfm" ] || "$bin" render "$s" --method pt --spp "$4" --bounces "$3" \
    -o "$out/$name.pt.pfm" > /dev/null 2>&1
  rm -f "$out/$name.$tag.pfm"  # never compare an older image
  "$bin" render "$s" --method "$method" --bounces "$3" "${options[@]}" -o "$out/$name.$tag.pfm" \
    > /dev/null
  local e
  e=$("$bin" compare "$out/$name.$tag.pfm" "$out/$name.pt.pfm" --radiance \
    --montage "$out/$name.$tag.montage.png" --json | python3 -c \
    'import json,sys; print("%.1f%%" % (100 * json.load(sys.stdin)["relative_rmse"]))')
  printf '%-16s %-4s %s\n' "$1" "$2" "$e"
}
for r in 0.1 0.3 0.6 1.0; do run sphere_metal $r 1 512; done
for r in 0.3 0.6 1.0; do run bunny_glossy $r 2 256; done
for r in 0.3 0.6; do run cornell_metal $r 2 256; done
for r in 0.3 0.6; do run gradient_metal $r 1 256; done
