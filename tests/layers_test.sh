#!/usr/bin/env bash
# The layers' include rule (docs/ARCHITECTURE.md): src/core, src/io and src/gpu include nothing
# of a world (src/flatland, src/spaceland) nor its public headers; src/analysis reaches the
# methods only through the public API (include/penumbra/...), never a world's sources or the GPU
# plumbing; public headers include only public headers; a world includes no other world.
#   layers_test.sh <source dir>
set -uo pipefail
cd "$1"
status=0
refuse() {  # refuse FOLDER PATTERN WHY
  local hits
  hits=$(grep -rnE --include='*.hpp' --include='*.cpp' --include='*.comp' --include='*.glsl' \
    "^[[:space:]]*#[[:space:]]*include[[:space:]]+[\"<]($2)" "$1" 2>/dev/null)
  if [ -n "$hits" ]; then
    echo "layers_test: $1 $3:" >&2
    echo "$hits" >&2
    status=1
  fi
}
for low in src/core src/io src/gpu; do
  refuse "$low" 'flatland/|spaceland/|analysis/|penumbra/flatland/|penumbra/spaceland/' \
    "must not include a world or the analysis"
done
refuse src/core 'io/|gpu/' "must include only core (io and gpu build on it)"
refuse src/analysis 'flatland/|spaceland/|gpu/' "reaches the methods only through include/penumbra/"
refuse include/penumbra 'core/|io/|gpu/|flatland/|spaceland/|analysis/' "public headers include only public headers"
refuse src/flatland 'spaceland/|penumbra/spaceland/|analysis/' "a world includes no other world"
if [ -d src/spaceland ]; then
  refuse src/spaceland 'flatland/|penumbra/flatland/|analysis/' "a world includes no other world"
fi
# The check itself must see the includes it guards against.
if ! grep -rqE '^#include "flatland/' src/flatland; then
  echo "layers_test: found no include of flatland/ in src/flatland: the pattern is broken" >&2
  status=1
fi
[ $status -eq 0 ] && echo "layers_test: the include rule holds"
exit $status
