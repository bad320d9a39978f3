#!/usr/bin/env bash
# The scene family's equal-error speed-ups (docs/QUALITY.md, "The scene family"): runs
# `penumbra bench-quality --quick` on every scene of BUILD/quality-family (written by
# quality-family.sh) at 1 and 2 bounces, each against its own 1024-spp reference (cached in
# BUILD/quality-cache/bench-family), and writes OUT/speedup.md: per scene and bounce count, SPWI's
# and the grid's error, time, the path tracer's time at that error (fitted on its 1-16 spp curve)
# and the speed-up, with the medians. Minutes on 2 cores.
#   bash scripts/family-speedup.sh BUILD OUT
set -euo pipefail
build=$1 out=$2
bin=$build/bin
scenes=$build/quality-family/scenes
work=$build/quality-family/bench
cache=$build/quality-cache/bench-family
mkdir -p "$out" "$work" "$cache"
rows=$work/rows.txt
: > "$rows"
for scene in "$scenes"/*.json; do
  name=$(basename "$scene" .json)
  for b in 1 2; do
    "$bin/penumbra" bench-quality "$scene" --quick --bounces "$b" -o "$work/${name}_b$b" \
      --cache "$cache" > /dev/null
    # The table's rows: | configuration | time | rel. RMSE | PSNR | bias | max | PT time | speed-up |
    for m in spwi grid; do
      sed -n "s/^| $m (defaults) | \([^|]*\) | \([^|]*\) | [^|]* | [^|]* | [^|]* | \([^|]*\) | \([^|]*\) |$/$name $b $m \1 \2 \3 \4/p" \
        "$work/${name}_b$b/quality.md" >> "$rows"
    done
  done
done
python3 - "$rows" "$out/speedup.md" <<'PY'
import statistics, sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
with open(sys.argv[2], "w") as f:
    f.write("| scene | bounces | method | rel. RMSE | time (ms) | path tracer at that error (ms) | speed-up |\n")
    f.write("| --- | ---: | --- | ---: | ---: | ---: | ---: |\n")
    for name, b, m, t, e, pt, s in rows:
        f.write(f"| {name} | {b} | {m} | {e} | {t} | {pt} | {s} |\n")
    f.write("\n| method | bounces | scenes | median speed-up | best | worst | scenes at 1x or more |\n")
    f.write("| --- | ---: | ---: | ---: | ---: | ---: | ---: |\n")
    for m in ("spwi", "grid"):
        for b in ("1", "2"):
            v = [float(r[6].rstrip("x")) for r in rows if r[2] == m and r[1] == b]
            if v:
                f.write(f"| {m} | {b} | {len(v)} | {statistics.median(v):.2g}x | {max(v):.2g}x | "
                        f"{min(v):.2g}x | {sum(x >= 1 for x in v)} |\n")
print(open(sys.argv[2]).read())
PY
