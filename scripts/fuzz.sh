#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, docs/RELIABILITY.md) with clang in build-fuzz and runs
# each for N seconds (default 60). A crash, a sanitizer report, a leak, an input slower than
# the timeout or memory over the limit fails the script; the input is kept under
# <build>/fuzz-work/artifacts/ (re-run it with: <build>/bin/<target> <file>).
#   scripts/fuzz.sh [seconds per target]
# Environment: FUZZ_BUILD (build-fuzz), JOBS (nproc), WERROR (OFF), FUZZ_TARGETS (all three).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
seconds=${1:-60}
build=${FUZZ_BUILD:-build-fuzz}
jobs=${JOBS:-$(nproc)}
targets=(${FUZZ_TARGETS:-fuzz_scene fuzz_image fuzz_strokes})

if ! command -v clang++-14 >/dev/null; then
  echo "fuzz.sh: clang++-14 is missing (scripts/install-deps.sh installs it)" >&2
  exit 1
fi
start=$SECONDS
CC=clang-14 CXX=clang++-14 cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release \
  -DPENUMBRA_FUZZ=ON -DPENUMBRA_BUILD_TESTS=OFF -DPENUMBRA_BUILD_BENCH=OFF \
  -DPENUMBRA_WERROR="${WERROR:-OFF}" >"$build.configure.log" 2>&1 ||
  { cat "$build.configure.log"; exit 1; }
# Only the fuzzers and the seed writer: the command line and the tools are not needed here.
cmake --build "$build" -j "$jobs" --target "${targets[@]}" penumbra_fuzz_seeds
echo "== fuzz.sh: build took $((SECONDS - start)) s"
start=$SECONDS

# Seeds, made afresh each run from files already in the repository and generated images.
work=$root/$build/fuzz-work
rm -rf "$work/seeds" "$work/layers"
mkdir -p "$work/seeds/scene" "$work/seeds/strokes" "$work/artifacts"
"$root/$build/bin/penumbra_fuzz_seeds" "$work/gen"
cp "$root"/scenes/*.json "$work/gen/scene/"* "$work/seeds/scene/"
cp "$root"/scenes/strokes/*.json "$work/seeds/strokes/"
printf '%s' '{"size": [16, 8], "strokes": [{"tool": "erase", "radius": 1, "points": [[1, 1]]}]}' \
  >"$work/seeds/strokes/erase.json"
# Layer paths in the seed scenes are relative to the fuzzer's working directory, $work: the
# examples' layers and the tiny generated ones.
mkdir -p "$work/layers"
cp "$root"/scenes/layers/* "$work/gen/layers/"* "$work/layers/"
rm -rf "$work/seeds/image"
cp -r "$work/gen/image" "$work/seeds/image"

failed=()
for t in "${targets[@]}"; do
  kind=${t#fuzz_}
  corpus=$work/corpus/$kind
  mkdir -p "$corpus"
  # Inputs up to 16 KiB: the largest example scene (124 KB) only slows each run, and an image
  # needs room for a header and an EXR's offset table (1024 entries for 16384 lines).
  echo "== fuzz.sh: $t for ${seconds}s"
  if (cd "$work" && "$root/$build/bin/$t" "$corpus" "$work/seeds/$kind" \
      -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=16384 \
      -artifact_prefix="$work/artifacts/$t-" -print_final_stats=1 \
      >"$work/$t.log" 2>&1); then
    grep -E '^#[0-9]+.*(DONE|pulse)' "$work/$t.log" | tail -1 || true
    grep -E '^stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)' "$work/$t.log" || true
  else
    tail -n 60 "$work/$t.log"
    echo "== fuzz.sh: $t FAILED (log: $work/$t.log, input under $work/artifacts/)"
    failed+=("$t")
  fi
done
echo "== fuzz.sh: runs took $((SECONDS - start)) s"
echo "fuzz: $((${#targets[@]} - ${#failed[@]})) passed, ${#failed[@]} failed"
[ ${#failed[@]} -eq 0 ] || { echo "fuzz.sh: failed: ${failed[*]}"; exit 1; }
