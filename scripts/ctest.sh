#!/usr/bin/env bash
# `make test`'s runner: ctest in the build folder $1 with $2 jobs, one short line per test
# (ctest pads each to the longest test name and announces every start) and its summary; a
# failing test's output in full. The exit code is ctest's.
set -euo pipefail
cd "$1"
ctest --output-on-failure -j "$2" "${@:3}" |
  sed -E -u -e '/^ +Start +[0-9]+: /d' -e 's/^( *[0-9]+\/[0-9]+ )Test +#[0-9]+: ([^ ]+) \.+ */\1\2 /' \
    -e 's/  +([0-9.]+ sec)$/ \1/'
