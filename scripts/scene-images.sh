#!/usr/bin/env bash
# Renders every picture of scenes/README.md with the command printed under it: the README is
# the list, so a picture and its command cannot drift apart. Prints each command's computation
# time (`--json`'s time_ms), the figure the README quotes. Stops at the first command that fails
# (its message is shown); the pictures after it are left as they were.
#   scripts/scene-images.sh [BUILD] [PATTERN]   (PATTERN: only commands containing it)
set -euo pipefail
source "$(dirname "$0")/readme-commands.sh"
readme_commands scene-images '^    build/bin/penumbra render scenes/' "$@"
for c in "${commands[@]}"; do
  [[ -z "$pattern" || "$c" == *"$pattern"* ]] || continue
  read -r -a args <<< "${c#build/bin/penumbra }"
  start=$(date +%s.%N)
  json=$("$build/bin/penumbra" "${args[@]}" --json -q)
  # The report's top-level "time_ms" (two spaces in: stages nest deeper).
  ms=$(printf '%s\n' "$json" | sed -n 's/^  "time_ms": \([^,]*\),\{0,1\}$/\1/p')
  [ -n "$ms" ] || { echo "scene-images: no time_ms in the report of: $c" >&2; exit 1; }
  awk -v ms="$ms" -v t0="$start" -v t1="$(date +%s.%N)" -v c="${c#build/bin/}" \
    'BEGIN { printf "%8.2f s computation  %7.2f s wall  %s\n", ms / 1000, t1 - t0, c }'
done
