#!/usr/bin/env bash
# The artifacts of holographic radiance cascades (seed 004, section 5.0.3), measured: the
# checkerboard with and without the cross blur, and the error against light size (moire of
# small lights), and issue 20's disk and two-light scenes. Writes the pictures next to this
# script and prints the tables of docs/QUALITY.md. Run from the repository root after
# `make build` (a few minutes: the path-traced references are rendered here, not cached).
set -euo pipefail
cd "$(dirname "$0")/../../.."
P=build/bin/penumbra
D=docs/quality/artifacts
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT

rmse() {  # rmse TEST REF [compare options...]: relative RMSE in percent
  local t=$1 r=$2
  shift 2
  "$P" compare "$t" "$r" "$@" --json | sed -n 's/.*"relative_rmse": \([^,]*\),*/\1/p' |
    awk '{ printf "%.2f%%", 100 * $1 }'
}

# The checkerboard: the occluder's penumbra near the occluder, with and without eq. 21.
S=scenes/occluder.json
"$P" render "$S" --method pt --nee --spp 1024 -q -o "$T/ref.pfm"
"$P" render "$S" --method hrc -q -o "$T/hrc.pfm"
"$P" render "$S" --method hrc --no-cross-blur -q -o "$T/noblur.pfm"
"$P" render "$S" -q -o "$T/rc.pfm"
CROP=(--crop 212 222 96 68)
echo "| occluder, cells 212..307 x 222..289 | rel. RMSE |"
echo "| --- | ---: |"
for m in hrc noblur rc; do
  echo "| $m | $(rmse "$T/$m.pfm" "$T/ref.pfm" --scene "$S" "${CROP[@]}") |"
done
"$P" compare "$T/noblur.pfm" "$T/ref.pfm" --scene "$S" "${CROP[@]}" --exposure 1 -q \
  --montage "$D/checker_noblur.png"
"$P" compare "$T/hrc.pfm" "$T/ref.pfm" --scene "$S" "${CROP[@]}" --exposure 1 -q \
  --montage "$D/checker_blur.png"

# Light size: a square light of side s cells, 96 cells left of a 14-cell occluder, 256^2; the
# relative RMSE over every open cell, and behind the occluder (cells 150..255 x 88..167, the
# shadow and its penumbrae).
BEHIND=(--crop 150 88 106 80)
echo
echo "| light side (cells) | HRC | HRC, no blur | RC (defaults) | HRC behind the occluder | HRC, no blur, behind | RC behind |"
echo "| ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
for s in 2 4 8 16 32; do
  cat > "$T/light$s.json" <<JSON
{ "penumbra": 1, "width": 256, "height": 256,
  "shapes": [ { "type": "box", "center": [40, 128], "size": [$s, $s],
                "emission": [$((1024 / (s * s) + 1)), $((1024 / (s * s) + 1)), $((1024 / (s * s) + 1))] },
              { "type": "box", "center": [136, 128], "size": [14, 14] } ] }
JSON
  "$P" render "$T/light$s.json" --method pt --nee --spp 2048 -q -o "$T/ref$s.pfm"
  "$P" render "$T/light$s.json" --method hrc -q -o "$T/hrc$s.pfm"
  "$P" render "$T/light$s.json" --method hrc --no-cross-blur -q -o "$T/noblur$s.pfm"
  "$P" render "$T/light$s.json" -q -o "$T/rc$s.pfm"
  row="| $s"
  for crop in "" "${BEHIND[*]}"; do
    for m in hrc noblur rc; do
      # shellcheck disable=SC2086 # the crop is four words
      row="$row | $(rmse "$T/$m$s.pfm" "$T/ref$s.pfm" --scene "$T/light$s.json" $crop)"
    done
  done
  echo "$row |"
done
"$P" compare "$T/hrc2.pfm" "$T/ref2.pfm" --scene "$T/light2.json" --exposure 2 -q \
  --montage "$D/small_light.png"
"$P" compare "$T/hrc2.pfm" "$T/ref2.pfm" --crop 8 96 64 64 -q --heatmap "$D/small_light_heat.png"

# Issue 20's scenes: the disk light of the tests (128^2, radius 12) and two disk lights with a
# slanted occluder (512^2), relative RMSE over the open cells against 4096-sample references,
# for HRC's defaults, each of its options and RC.
echo
echo "| scene | HRC | --corners walls | --blur-near-segment | --no-cross-blur | --wall-fan 0 | --even-weight 0.5 | RC (defaults) |"
echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
cat > "$T/disk.json" <<JSON
{ "penumbra": 1, "width": 128, "height": 128,
  "shapes": [ { "type": "circle", "center": [64.3, 63.8], "radius": 12, "emission": [2.5, 2.5, 2.5] } ] }
JSON
cp scenes/two_lights.json "$T/two_lights.json"
for name in disk two_lights; do
  S="$T/$name.json"
  "$P" render "$S" --method pt --nee --spp 4096 -q -o "$T/${name}_ref.pfm"
  row="| $name"
  for opts in "" "--corners walls" "--blur-near-segment" "--no-cross-blur" "--wall-fan 0" \
    "--even-weight 0.5"; do
    # shellcheck disable=SC2086 # the options are words
    "$P" render "$S" --method hrc $opts -q -o "$T/${name}_hrc.pfm"
    row="$row | $(rmse "$T/${name}_hrc.pfm" "$T/${name}_ref.pfm" --scene "$S")"
  done
  "$P" render "$S" -q -o "$T/${name}_rc.pfm"
  echo "$row | $(rmse "$T/${name}_rc.pfm" "$T/${name}_ref.pfm" --scene "$S") |"
done

# A diagonal wall edge of the built-in scene, lit from above: HRC against the path tracer.
"$P" render --method pt --nee --spp 256 -q -o "$T/default_ref.pfm"
"$P" render --method hrc -q -o "$T/default_hrc.pfm"
"$P" compare "$T/default_hrc.pfm" "$T/default_ref.pfm" --crop 280 120 80 80 --exposure 1 -q \
  --montage "$D/diagonal_edge.png"
# The same without the wall fan: wall cells read through the cell beside them (the staircase).
"$P" render --method hrc --wall-fan 0 -q -o "$T/default_hrc_no_fan.pfm"
"$P" compare "$T/default_hrc_no_fan.pfm" "$T/default_ref.pfm" --crop 280 120 80 80 --exposure 1 \
  -q --montage "$D/diagonal_edge_no_fan.png"
