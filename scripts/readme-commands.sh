# Sourced by the scripts that run the commands printed in scenes/README.md (scene-images.sh,
# reference-error.sh): `readme_commands NAME REGEX [BUILD] [PATTERN]` sets `build` (absolute, with
# bin/penumbra in it), `pattern`, and `commands`, the README's command lines matching REGEX
# (extended), from the repository root; it exits naming NAME where there is no build or no
# command.
readme_commands() {
  local name=$1 regex=$2
  build=$(realpath "${3:-build}")
  pattern=${4:-}
  cd "$(dirname "${BASH_SOURCE[0]}")/.."
  [ -x "$build/bin/penumbra" ] || { echo "$name: no $build/bin/penumbra (make build)" >&2; exit 1; }
  mapfile -t commands < <(grep -E "$regex" scenes/README.md | sed -e 's/^ *//')
  [ ${#commands[@]} -gt 0 ] || { echo "$name: no commands in scenes/README.md" >&2; exit 1; }
}
