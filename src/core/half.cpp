#include "core/half.hpp"

#include <immintrin.h>

#include <cstdlib>

namespace penumbra {
namespace {

[[gnu::target("f16c,avx")]] void to_float_f16c(const Half* s, float* d, int n) {
  int i = 0;
  for (; i + 8 <= n; i += 8)
    _mm256_storeu_ps(d + i,
                     _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(s + i))));
  for (; i < n; ++i) d[i] = float(s[i]);
}

[[gnu::target("f16c,avx")]] void to_half_f16c(const float* s, Half* d, int n) {
  int i = 0;
  for (; i + 8 <= n; i += 8)
    _mm_storeu_si128(reinterpret_cast<__m128i*>(d + i),
                     _mm256_cvtps_ph(_mm256_loadu_ps(s + i), _MM_FROUND_TO_NEAREST_INT));
  for (; i < n; ++i) d[i] = Half(s[i]);
}

// Initialised before main, so the CPU model is initialised here rather than assumed.
const bool kHasF16c = [] {
  __builtin_cpu_init();
  const char* off = std::getenv("PENUMBRA_NO_F16C");
  return !(off && *off && *off != '0') && __builtin_cpu_supports("f16c") &&
         __builtin_cpu_supports("avx");
}();

}  // namespace

void to_float(const Half* s, float* d, int n) {
  if (kHasF16c) return to_float_f16c(s, d, n);
  for (int i = 0; i < n; ++i) d[i] = float(s[i]);
}

void to_half(const float* s, Half* d, int n) {
  if (kHasF16c) return to_half_f16c(s, d, n);
  for (int i = 0; i < n; ++i) d[i] = Half(s[i]);
}

}  // namespace penumbra
