// The median of timings (benchmarks and the painter's frame times), and quantiles of values
// (the display's exposure meter, the comparison's PSNR peak and heatmap scale).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace penumbra {

// The value at rank floor(q n) (the largest for q = 1) of `v`, which is reordered (nth_element,
// linear time); `v` must not be empty. q = 0.5 is the upper middle value for an even count.
template <class T>
T quantile(std::vector<T>& v, double q) {
  const auto at =
      v.begin() + std::ptrdiff_t(std::min(v.size() - 1, std::size_t(q * double(v.size()))));
  std::nth_element(v.begin(), at, v.end());
  return *at;
}

// The middle value (the mean of the two middle ones for an even count); 0 for none.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace penumbra
