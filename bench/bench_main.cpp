// penumbra_bench's front end: Google Benchmark's flags (--help lists them), plus --version, and
// the exit codes every Penumbra program uses (2 for a flag it does not know).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstring>

#include "penumbra/version.hpp"

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::strcmp(argv[i], "--version") == 0) {
      std::printf("penumbra_bench (penumbra %s, Google Benchmark)\n", penumbra::kVersion);
      return 0;
    }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  // Debian builds libbenchmark without NDEBUG, so its reporter warns "Library was built as
  // DEBUG". Our code is built as the build type says (Release by default); the library's part
  // of a measurement is the loop's bookkeeping, inlined from its header (docs/PERFORMANCE.md).
  std::fprintf(stderr,
               "penumbra_bench: the DEBUG warning below is about Debian's build of Google "
               "Benchmark, not Penumbra's code (docs/PERFORMANCE.md)\n");
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
