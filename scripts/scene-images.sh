#!/usr/bin/env bash
# Renders every picture of scenes/README.md with the command printed under it: the README is
# the list, so a picture and its command cannot drift apart. Prints each command's computation
# time (`--json`'s time_ms), the figure the README quotes.
#   scripts/scene-images.sh [BUILD] [PATTERN]   (PATTERN: only commands containing it)
set -euo pipefail
build=${1:-build}
pattern=${2:-}
cd "$(dirname "$0")/.."
mapfile -t commands < <(grep -E '^    build/bin/penumbra render scenes/' scenes/README.md |
                        sed -e 's/^ *//' -e "s#^build/#$build/#")
[ ${#commands[@]} -gt 0 ] || { echo "scene-images: no commands in scenes/README.md" >&2; exit 1; }
for c in "${commands[@]}"; do
  [[ -z "$pattern" || "$c" == *"$pattern"* ]] || continue
  read -r -a args <<< "$c"
  start=$(date +%s.%N)
  json=$("${args[@]}" --json -q)
  ms=$(printf '%s\n' "$json" | grep -m1 '^  "time_ms"' | tr -dc '0-9.')
  awk -v ms="$ms" -v t0="$start" -v t1="$(date +%s.%N)" -v c="${c#"$build"/bin/}" \
    'BEGIN { printf "%8.2f s computation  %7.2f s wall  %s\n", ms / 1000, t1 - t0, c }' 
done
