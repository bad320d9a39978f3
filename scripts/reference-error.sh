#!/usr/bin/env bash
# The own error of each path-traced picture of scenes/README.md (the 3D scenes' commands): the
# command run twice to PFM, with seeds 0 and 1, and their relative RMSE over sqrt 2 (two
# independent estimates differ by sqrt 2 times either's error). Prints it with the command; the
# README quotes it under each picture, so a user knows how far the picture they compare with is
# from converged.
#   scripts/reference-error.sh [BUILD] [PATTERN]   (PATTERN: only commands containing it)
set -euo pipefail
source "$(dirname "$0")/readme-commands.sh"
readme_commands reference-error '^    build/bin/penumbra render scenes/3d/' "$@"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for c in "${commands[@]}"; do
  [[ -z "$pattern" || "$c" == *"$pattern"* ]] || continue
  read -r -a args <<< "${c#build/bin/penumbra }"
  # The same command to PFM (the picture's -o and exposure dropped), at two seeds.
  run=()
  skip=0
  for a in "${args[@]}"; do
    if [ $skip = 1 ]; then skip=0; continue; fi
    case "$a" in -o|--exposure) skip=1; continue ;; esac
    run+=("$a")
  done
  "$build/bin/penumbra" "${run[@]}" -o "$work/a.pfm" -q
  "$build/bin/penumbra" "${run[@]}" --seed 1 -o "$work/b.pfm" -q
  e=$("$build/bin/penumbra" compare "$work/b.pfm" "$work/a.pfm" --radiance --json |
    sed -n 's/^ *"relative_rmse": \([^,]*\),*$/\1/p')
  awk -v e="$e" -v c="${c#build/bin/}" 'BEGIN { printf "%6.2f%%  %s\n", 100 * e / sqrt(2), c }'
done
