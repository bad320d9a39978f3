// Error metrics of one linear image against another, and the scene mask they are taken over.
#include "penumbra/compare.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/median.hpp"
#include "penumbra/flatland/compare.hpp"

namespace penumbra {

Status check_finite(const ImageRgb& image, const std::string& name) {
  const float* p = image.data();
  for (std::size_t k = 0; k < image.size(); ++k) {
    if (std::isfinite(p[k])) continue;
    const std::size_t cell = k / 3;
    const int x = static_cast<int>(cell % image.width()),
              y = static_cast<int>(cell / image.width());
    return Error{name + ": cell (" + std::to_string(x) + ", " + std::to_string(y) +
                 ") holds a non-finite value (" + std::to_string(p[k]) + ")"};
  }
  return {};
}

Expected<ErrorMetrics> compare_images(const ImageRgb& test, const ImageRgb& ref,
                                      const std::vector<std::uint8_t>* mask) {
  auto size = [](int w, int h) { return std::to_string(w) + "x" + std::to_string(h); };
  if (test.width() != ref.width() || test.height() != ref.height())
    return Error{"the test image is " + size(test.width(), test.height()) +
                 " but the reference is " + size(ref.width(), ref.height())};
  const std::size_t cells = std::size_t(ref.width()) * ref.height();
  if (mask && mask->size() != cells)
    return Error{"the mask has " + std::to_string(mask->size()) + " cells, the images " +
                 size(ref.width(), ref.height()) + " = " + std::to_string(cells)};
  if (Status s = check_finite(test, "the test image"); !s) return s.error();
  if (Status s = check_finite(ref, "the reference image"); !s) return s.error();

  double sum_sq = 0, sum_abs = 0, sum_e = 0, sum_ref = 0, max_abs = 0;
  std::vector<float> values;  // REF's counted values, for the peak
  values.reserve(3 * cells);
  std::uint64_t counted = 0;
  const float* t = test.data();
  const float* r = ref.data();
  for (std::size_t i = 0; i < cells; ++i) {
    if (mask && (*mask)[i] == 0) continue;
    ++counted;
    for (std::size_t k = i * 3; k < i * 3 + 3; ++k) {
      const double e = double(t[k]) - double(r[k]);
      sum_sq += e * e;
      sum_abs += std::abs(e);
      sum_e += e;
      sum_ref += r[k];
      max_abs = std::max(max_abs, std::abs(e));
      values.push_back(r[k]);
    }
  }
  if (counted == 0) return Error{"no cell to compare: the mask leaves out every cell"};

  const double n = 3.0 * double(counted);
  ErrorMetrics m;
  m.cells = counted;
  m.rmse = std::sqrt(sum_sq / n);
  m.mean_abs = sum_abs / n;
  m.max_abs = max_abs;
  m.bias = sum_e / n;
  m.reference_mean = sum_ref / n;
  // The peak: REF's 99th percentile, not its maximum, which a light's own cells would set.
  const double peak = quantile(values, kPsnrPeakQuantile);
  m.psnr_peak = peak;
  const double inf = std::numeric_limits<double>::infinity();
  if (m.rmse == 0) {
    m.relative_rmse = 0;
    m.psnr = inf;
  } else {
    m.relative_rmse = m.reference_mean > 0 ? m.rmse / m.reference_mean : inf;
    m.psnr = peak > 0 ? 20 * std::log10(peak / m.rmse) : std::numeric_limits<double>::quiet_NaN();
  }
  return m;
}

}  // namespace penumbra

namespace penumbra::flatland {

std::vector<std::uint8_t> non_opaque_cells(const Scene& scene) {
  std::vector<std::uint8_t> mask(scene.opacity.size());
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = scene.opacity[i] < 1.0f ? 1 : 0;
  return mask;
}

}  // namespace penumbra::flatland
