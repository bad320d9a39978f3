#!/usr/bin/env bash
# Frame times of `penumbra view` on every 3D example scene with each method, at the default view
# size and internal resolution (docs/PERFORMANCE.md, "The 3D viewer"). Needs a display: it starts
# one with xvfb-run where DISPLAY is unset.
#   scripts/view-frame-times.sh BUILD [FRAMES] > table.md
# METHODS="grid" runs some methods only (default: ssrc spwi surface grid).
set -euo pipefail
build=${1:?usage: view-frame-times.sh BUILD [FRAMES]}
frames=${2:-20}
cli=$build/bin/penumbra
run() {
  if [ -n "${DISPLAY:-}" ]; then "$@"; else xvfb-run -a -s "-screen 0 1600x1000x24" "$@"; fi
}
echo "| scene | method | view | internal (median) | frame median, ms | slowest stages (median ms) |"
echo "|---|---|---|---|---|---|"
for scene in scenes/3d/*.json; do
  for method in ${METHODS:-ssrc spwi surface grid}; do
    out=$(run "$cli" view "$scene" --method "$method" --frames "$frames" --stats 2>&1) || {
      why=$(printf '%s\n' "$out" | grep -m1 'refused\|penumbra view:' | sed 's/.*refused: //; s/|/\\|/g' | cut -c1-90)
      echo "| $(basename "$scene" .json) | $method | | | refused | $why |"
      continue
    }
    view=$(printf '%s\n' "$out" | sed -n 's/.*, \([0-9]*x[0-9]*\) view,.*/\1/p')
    internal=$(printf '%s\n' "$out" | sed -n 's/.*internal resolution: median \([0-9x]*\).*/\1/p')
    frame=$(printf '%s\n' "$out" | sed -n 's/.*frame (render()): median \([0-9.]*\) ms.*/\1/p')
    # "    cascade 0              median   58.90 ms" -> "cascade 0 58.9", the three slowest.
    stages=$(printf '%s\n' "$out" | awk '/^    .* median +[0-9.]+ ms$/ {
        ms = $(NF - 1); name = $0; sub(/ +median +[0-9.]+ ms$/, "", name); sub(/^ +/, "", name)
        print ms "\t" name }' | sort -rn | head -3 |
      awk -F'\t' '{ printf "%s%s %s", (NR > 1 ? ", " : ""), $2, $1 }')
    echo "| $(basename "$scene" .json) | $method | $view | $internal | $frame | $stages |"
  done
done
