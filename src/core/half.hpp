// Half-precision floats (IEEE binary16, Imath's half): conversions of runs of values, 8 at a time
// with F16C where the CPU has it (every x86-64 CPU since 2012; the build targets the baseline, so
// it is chosen at run time), otherwise through Imath's tables. Both round to nearest even: the
// same bits. PENUMBRA_NO_F16C=1 forces the tables (the tests compare the two).
#pragma once

#include <Imath/half.h>

namespace penumbra {

using Half = Imath::half;

inline float load(float v) {
  return v;
}
inline float load(Half v) {
  return float(v);
}

// n values from s to d.
void to_float(const Half* s, float* d, int n);
void to_half(const float* s, Half* d, int n);

}  // namespace penumbra
