#include "core/half.hpp"

#include <cpuid.h>
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

// F16C and AVX from CPUID, and the AVX registers enabled by the OS (XGETBV). Read directly:
// clang 14's __builtin_cpu_supports does not know "f16c".
bool cpu_has_f16c_avx() {
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (!__get_cpuid(1, &a, &b, &c, &d)) return false;
  if (!(c & bit_F16C) || !(c & bit_AVX) || !(c & bit_OSXSAVE)) return false;
  unsigned lo = 0, hi = 0;
  __asm__("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
  return (lo & 6) == 6;  // XMM and YMM state saved by the OS
}

// Initialised before main.
const bool kHasF16c = [] {
  const char* off = std::getenv("PENUMBRA_NO_F16C");
  return !(off && *off && *off != '0') && cpu_has_f16c_avx();
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
