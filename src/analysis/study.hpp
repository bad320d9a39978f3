// The quality study: every method at its settings against a converged path-traced reference,
// as error against time (penumbra bench-quality, docs/QUALITY.md).
#pragma once

#include <string>
#include <vector>

#include "penumbra/compare.hpp"
#include "penumbra/flatland/render.hpp"

namespace penumbra::study {

using namespace penumbra::flatland;  // the study renders 2D scenes

// One configuration to run. Rows of the same `curve` (the path tracer at growing sample counts)
// are drawn as one line; the others as single points.
struct Run {
  std::string label;
  std::string curve;  // "pt", "pt nee", or empty for a single point
  RenderOptions options;
};

// The path tracer at 1, 4, 16, ... samples per cell up to `max_spp`, plain and with NEE; the
// cascades (RC and HRC) at their defaults and the variants docs/METHODS.md lists. All use
// `bounces`.
std::vector<Run> default_runs(int bounces, int max_spp, bool quick);

// One measured configuration, of either world.
struct Row {
  std::string label;
  std::string curve;   // as Run::curve
  std::string method;  // the method's name (pt, rc, hrc, spwi, ...)
  double time_ms = 0;
  std::uint64_t samples = 0;
  ErrorMetrics error;
  // Time the NEE path tracer needs for the same relative RMSE (log-log interpolation along its
  // curve; extrapolated from the last two points beyond it). NaN when there is no curve.
  double pt_equal_time_ms = 0;
  bool extrapolated = false;
};

// Time at which a curve of rows (increasing samples, falling error) reaches `relative_rmse`, by
// linear interpolation of log(time) against log(error) between the two nearest points;
// `extrapolated` when the error lies outside the curve's range. NaN with fewer than 2 points.
double equal_error_time(const std::vector<Row>& curve, double relative_rmse, bool& extrapolated);

// Fills pt_equal_time_ms of every row from the "pt nee" curve among them.
void add_equal_error_times(std::vector<Row>& rows);

// Exponent k of error ~ spp^-k fitted (least squares in log-log) to a curve's rows.
double convergence_order(const std::vector<Row>& rows, const std::string& curve);

struct Reference {
  std::string path;           // where the reference image is cached
  int spp = 0;                // samples per cell (2D) or pixel (3D)
  double time_ms = 0;         // how long rendering it took (0 when it came from the cache)
  double estimated_rel = 0;   // its own relative RMSE, extrapolated along the NEE curve
  std::string unit = "cell";  // what a sample is taken for: "cell" (2D) or "pixel" (3D)
};

std::string to_csv(const std::vector<Row>& rows);
std::string to_markdown(const std::vector<Row>& rows, const std::string& scene,
                        const Reference& reference);
// A log-log plot of relative RMSE against time, one line per curve and a labelled dot per
// single configuration.
std::string to_svg(const std::vector<Row>& rows, const std::string& title);
// The same plot as a picture.
ImageRgb8 to_png_plot(const std::vector<Row>& rows, const std::string& title);

// A study's section in a markdown document (docs/QUALITY.md) lies between the lines
// `<!-- bench-quality NAME -->` and `<!-- /bench-quality NAME -->`. Returns `doc` with what lies
// between them replaced by `body`, or an Error saying which marker is missing.
Expected<std::string> splice_section(const std::string& doc, const std::string& name,
                                     const std::string& body);

// A 64-bit hash of everything that determines a scene's fluence (size, environment, every
// layer), to name cached references.
std::uint64_t scene_hash(const Scene& scene);

}  // namespace penumbra::study
