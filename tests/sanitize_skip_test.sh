#!/usr/bin/env bash
# Every name in tests/sanitize-skip.txt is a test of the test binary, so that a renamed test is
# not run under the sanitizers by accident, nor a stale name kept.
#   sanitize_skip_test.sh <penumbra_tests> <sanitize-skip.txt>
set -euo pipefail
tests=$("$1" --gtest_list_tests | awk '/^[^ ]/ { suite = $1 } /^  / { print suite $1 }')
missing=0
while read -r name; do
  if ! grep -qxF "$name" <<<"$tests"; then
    echo "$2: $name is not a test" >&2
    missing=1
  fi
done < <(sed -e 's/#.*//' "$2" | awk 'NF { print $1 }')
exit $missing
