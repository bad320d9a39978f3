// A slice of the scene family (tools/scene_family.cpp, docs/QUALITY.md "The scene family") in
// every test run: one scene of each class at 64 x 48, SPWI and the probe grid at their defaults
// against the path tracer. The references are path traced here (256 spp, with a second seed whose
// distance from the first bounds their own error), and each method's error must stay under what
// was measured, with room for the references' noise: a change that breaks the methods on the
// scenes users make fails here, not only in `make quality`.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "penumbra/compare.hpp"
#include "penumbra/spaceland/render.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "test_support.hpp"

namespace penumbra::spaceland {
namespace {

ImageRgb rendered(const Scene& s, RenderOptions o) {
  Expected<RenderResult> r = render(s, o);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.ok() ? std::move(r->radiance) : ImageRgb(1, 1);
}

double error_of(const ImageRgb& test, const ImageRgb& ref) {
  Expected<ErrorMetrics> m = compare_images(test, ref);
  EXPECT_TRUE(m.ok());
  return m.ok() ? m->relative_rmse : 1e9;
}

// Measured 2026-11-27 (relative RMSE against the 256-spp reference): SPWI (s0 2 at this size;
// 0.356, 0.591 and 0.274 at s0 4; night_0 0.106 before its lights' shares were made exact for the
// gather, behind_0 0.378 before its panel was claimed as a shaped light), the grid (night_0 0.261
// before its cascade 0 was met at the shaded point).
struct Slice {
  const char* name;
  double spwi, grid;
};
constexpr Slice kSlice[] = {
    {"night_0", 0.101, 0.097},
    {"behind_0", 0.105, 0.429},
    {"window_0", 0.271, 0.263},
};

TEST(Family, ASliceStaysNearThePathTracer) {
  penumbra::testing::TestDir dir("family");
  const penumbra::testing::CliResult made = penumbra::testing::run_program(
      PENUMBRA_SCENE_FAMILY, {"scenes", "--count", "1", "--width", "64", "--height", "48"},
      dir.root(), true);
  ASSERT_EQ(made.status, 0) << made.err;
  for (const Slice& slice : kSlice) {
    Expected<Scene> s =
        load_scene((dir.root() / "scenes" / (std::string(slice.name) + ".json")).string());
    ASSERT_TRUE(s.ok()) << s.error().message;
    RenderOptions o;
    o.pt.spp = 256;
    const ImageRgb ref = rendered(*s, o);
    o.pt.seed = 1;
    // The reference's own error: two of them differ by sqrt 2 times it.
    const double own = error_of(rendered(*s, o), ref) / std::sqrt(2.0);
    EXPECT_LT(own, 0.06) << slice.name;
    // What was measured, a fifth more, and three times the reference's own error.
    o.method = Method::spwi;
    EXPECT_LT(error_of(rendered(*s, o), ref), 1.2 * slice.spwi + 3 * own) << slice.name;
    o.method = Method::grid;
    EXPECT_LT(error_of(rendered(*s, o), ref), 1.2 * slice.grid + 3 * own) << slice.name;
  }
}

}  // namespace
}  // namespace penumbra::spaceland
