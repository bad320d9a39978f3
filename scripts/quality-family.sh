#!/usr/bin/env bash
# The scene family study (docs/QUALITY.md, "The scene family"): writes the random scenes of
# penumbra_scene_family into BUILD/quality-family, path traces each at 1 and 2 bounces (cached),
# renders it with SPWI, the probe grid and the surface cascades at their defaults (METHODS, a
# space-separated list in the environment, picks some of them), and writes each render's relative
# RMSE against the reference and its time into OUT/family.md, with the median and the worst per
# method and bounce count, and montages of the worst (OUT/worst_*.png). The reference's own error
# is estimated from a second one of another seed: their relative RMSE over sqrt 2.
#   bash scripts/quality-family.sh BUILD OUT [COUNT] [REFERENCE_SPP]
set -euo pipefail
build=$1 out=$2 count=${3:-4} spp=${4:-1024}
methods=${METHODS:-spwi grid surface}
bin=$build/bin
cache=$build/quality-cache/family
work=$build/quality-family
mkdir -p "$out" "$work/scenes" "$work/renders" "$cache"
"$bin/penumbra_scene_family" "$work/scenes" --count "$count" > /dev/null

# A value of a flat JSON report (penumbra's --json output), by key.
value() { sed -n "s/^ *\"$1\": \([^,]*\),*$/\1/p" | head -1; }

rows=$work/rows.txt
: > "$rows"
for scene in "$work"/scenes/*.json; do
  name=$(basename "$scene" .json)
  for bounces in 1 2; do
    # The reference, cached under the scene's checksum (a new seed or generator writes anew).
    sum=$(cksum < "$scene" | cut -d' ' -f1)
    ref=$cache/${name}_b${bounces}_${spp}_${sum}.pfm
    twin=$cache/${name}_b${bounces}_${spp}_${sum}_seed1.pfm
    if [ ! -f "$ref" ]; then
      "$bin/penumbra" render "$scene" --method pt --spp "$spp" --bounces "$bounces" -o "$ref" -q
    fi
    if [ ! -f "$twin" ]; then
      "$bin/penumbra" render "$scene" --method pt --spp "$spp" --bounces "$bounces" --seed 1 \
        -o "$twin" -q
    fi
    own=$("$bin/penumbra" compare "$twin" "$ref" --radiance --json | value relative_rmse)
    for method in $methods; do
      img=$work/renders/${name}_b${bounces}_${method}.pfm
      ms=$("$bin/penumbra" render "$scene" --method "$method" --bounces "$bounces" -o "$img" \
        --json | value time_ms)
      err=$("$bin/penumbra" compare "$img" "$ref" --radiance --json | value relative_rmse)
      echo "$name $bounces $method $err $ms $own" >> "$rows"
    done
  done
done

# The table, then per method and bounce count the median and the worst (and its montage).
{
  echo "| scene | bounces | method | relative RMSE | time (ms) | the reference's own |"
  echo "| --- | ---: | --- | ---: | ---: | ---: |"
  awk '{ printf "| %s | %s | %s | %.1f%% | %.0f | %.1f%% |\n", $1, $2, $3, 100 * $4, $5,
         100 * $6 / sqrt(2) }' "$rows"
  echo
  echo "| method | bounces | scenes | median | worst (scene) |"
  echo "| --- | ---: | ---: | ---: | --- |"
  for method in $methods; do
    for bounces in 1 2; do
      awk -v m="$method" -v b="$bounces" '$3 == m && $2 == b { print $4, $1 }' "$rows" | sort -g |
        awk -v m="$method" -v b="$bounces" '
          { e[NR] = $1; s[NR] = $2 }
          END {
            med = NR % 2 ? e[(NR + 1) / 2] : (e[NR / 2] + e[NR / 2 + 1]) / 2
            printf "| %s | %s | %d | %.1f%% | %.1f%% (%s) |\n", m, b, NR, 100 * med, 100 * e[NR], s[NR]
          }'
    done
  done
} > "$out/family.md"
for method in $methods; do
  for bounces in 1 2; do
    worst=$(awk -v m="$method" -v b="$bounces" '$3 == m && $2 == b { print $4, $1 }' "$rows" |
      sort -g | tail -1 | cut -d' ' -f2)
    sum=$(cksum < "$work/scenes/$worst.json" | cut -d' ' -f1)
    "$bin/penumbra" compare "$work/renders/${worst}_b${bounces}_${method}.pfm" \
      "$cache/${worst}_b${bounces}_${spp}_${sum}.pfm" --radiance -q \
      --montage "$out/worst_${method}_b${bounces}.png"
  done
done
cat "$out/family.md"
