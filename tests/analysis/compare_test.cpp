// Comparing images: metrics against hand-computed values, the scene mask, the pictures (read back
// from PNG), and `penumbra compare` as a user runs it.
#include "penumbra/compare.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/pictures.hpp"
#include "io/image_io.hpp"
#include "penumbra/flatland/compare.hpp"
#include "penumbra/flatland/io.hpp"
#include "penumbra/flatland/scene.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using penumbra::ErrorMetrics;
using penumbra::ImageRgb;
using penumbra::ImageRgb8;

ImageRgb image(int w, int h, const std::vector<float>& values) {
  return ImageRgb(w, h, std::vector<float>(values));
}

// 2x1 images. Per value e = TEST - REF: cell 0 (3,1,2) - (1,1,1) = (2,0,1), cell 1
// (2,2,2) - (2,2,4) = (0,0,-2). Over n = 6 values: sum e = 1, sum |e| = 5, sum e^2 = 9,
// max |e| = 2, sum REF = 11, largest REF = 4.
const ImageRgb kTest = image(2, 1, {3, 1, 2, 2, 2, 2});
const ImageRgb kRef = image(2, 1, {1, 1, 1, 2, 2, 4});

TEST(CompareMetrics, HandComputedValues) {
  const auto m = penumbra::compare_images(kTest, kRef);
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->cells, 2u);
  EXPECT_DOUBLE_EQ(m->rmse, std::sqrt(9.0 / 6));  // 1.2247...
  EXPECT_NEAR(m->rmse, 1.2247449, 1e-7);
  EXPECT_DOUBLE_EQ(m->bias, 1.0 / 6);
  EXPECT_DOUBLE_EQ(m->mean_abs, 5.0 / 6);
  EXPECT_DOUBLE_EQ(m->max_abs, 2.0);
  EXPECT_DOUBLE_EQ(m->reference_mean, 11.0 / 6);
  EXPECT_NEAR(m->relative_rmse, 0.6680427, 1e-7);  // 1.2247 / (11/6)
  EXPECT_NEAR(m->psnr, 10.2802872, 1e-6);          // 20 log10(4 / 1.2247)
}

// PSNR's peak is the reference's 99th percentile: one cell of a light 1000 times brighter than
// the rest no longer sets it (it set 60 dB more before).
TEST(CompareMetrics, PsnrPeakIsTheReferences99thPercentile) {
  std::vector<float> ref(20 * 10 * 3, 1.0f), test(ref.size(), 1.1f);
  ref[0] = ref[1] = ref[2] = 1000;  // 3 of 600 values: above the 99th percentile
  test[0] = test[1] = test[2] = 1000;
  const auto m = penumbra::compare_images(image(20, 10, test), image(20, 10, ref));
  ASSERT_TRUE(m.ok());
  EXPECT_DOUBLE_EQ(m->psnr_peak, 1.0);
  EXPECT_NEAR(m->psnr, 20 * std::log10(1.0 / m->rmse), 1e-9);
  // A light over more than 1% of the values does set it.
  for (std::size_t k = 3; k < 9; ++k) ref[k] = test[k] = 1000;
  const auto n = penumbra::compare_images(image(20, 10, test), image(20, 10, ref));
  ASSERT_TRUE(n.ok());
  EXPECT_DOUBLE_EQ(n->psnr_peak, 1000.0);
}

TEST(CompareMetrics, SwappingTheImagesFlipsTheBiasOnly) {
  const auto ab = penumbra::compare_images(kTest, kRef);
  const auto ba = penumbra::compare_images(kRef, kTest);
  ASSERT_TRUE(ab.ok() && ba.ok());
  EXPECT_DOUBLE_EQ(ba->bias, -ab->bias);
  EXPECT_DOUBLE_EQ(ba->rmse, ab->rmse);
  EXPECT_DOUBLE_EQ(ba->reference_mean, 12.0 / 6);  // now kTest is the reference
}

TEST(CompareMetrics, IdenticalImagesHaveZeroErrorAndInfinitePsnr) {
  const auto m = penumbra::compare_images(kRef, kRef);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->rmse, 0.0);
  EXPECT_EQ(m->relative_rmse, 0.0);
  EXPECT_EQ(m->max_abs, 0.0);
  EXPECT_EQ(m->bias, 0.0);
  EXPECT_TRUE(std::isinf(m->psnr) && m->psnr > 0);
}

TEST(CompareMetrics, BlackReferenceGivesInfiniteRelativeErrorAndNoPsnr) {
  const auto m = penumbra::compare_images(image(1, 1, {1, 1, 1}), image(1, 1, {0, 0, 0}));
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->rmse, 1.0);
  EXPECT_TRUE(std::isinf(m->relative_rmse));
  EXPECT_TRUE(std::isnan(m->psnr));
}

TEST(CompareMetrics, MaskCountsOnlyMarkedCells) {
  // Cell 1 only: e = (0, 0, -2).
  const std::vector<std::uint8_t> mask = {0, 1};
  const auto m = penumbra::compare_images(kTest, kRef, &mask);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->cells, 1u);
  EXPECT_DOUBLE_EQ(m->rmse, std::sqrt(4.0 / 3));
  EXPECT_DOUBLE_EQ(m->bias, -2.0 / 3);
  EXPECT_DOUBLE_EQ(m->reference_mean, 8.0 / 3);
}

TEST(CompareMetrics, RefusesWhatCannotBeCompared) {
  const auto sizes = penumbra::compare_images(kTest, image(1, 2, {1, 1, 1, 1, 1, 1}));
  ASSERT_FALSE(sizes.ok());
  EXPECT_NE(sizes.error().message.find("2x1"), std::string::npos) << sizes.error().message;
  EXPECT_NE(sizes.error().message.find("1x2"), std::string::npos) << sizes.error().message;

  const std::vector<std::uint8_t> short_mask = {1};
  EXPECT_FALSE(penumbra::compare_images(kTest, kRef, &short_mask).ok());

  const std::vector<std::uint8_t> none = {0, 0};
  const auto empty = penumbra::compare_images(kTest, kRef, &none);
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(empty.error().message.find("no cell"), std::string::npos) << empty.error().message;

  ImageRgb nan = kTest;
  nan.set(1, 0, {0, std::numeric_limits<float>::quiet_NaN(), 0});
  const auto bad = penumbra::compare_images(nan, kRef);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("test"), std::string::npos) << bad.error().message;
  EXPECT_NE(bad.error().message.find("(1, 0)"), std::string::npos) << bad.error().message;
}

// 4x2 cells, the left 2x2 covered by an opaque box.
penumbra::flatland::Scene boxed_scene() {
  penumbra::flatland::SceneDesc desc;
  desc.width = 4;
  desc.height = 2;
  desc.shapes.push_back(
      {penumbra::flatland::Box{{1, 1}, {2, 2}, 0}, penumbra::flatland::Material{}});
  auto scene = penumbra::flatland::build_scene(desc);
  EXPECT_TRUE(scene.ok()) << scene.error().message;
  return *scene;
}

TEST(CompareMetrics, SceneMaskLeavesOutOpaqueCells) {
  const penumbra::flatland::Scene scene = boxed_scene();
  const std::vector<std::uint8_t> mask = penumbra::flatland::non_opaque_cells(scene);
  EXPECT_EQ(mask, (std::vector<std::uint8_t>{0, 0, 1, 1, 0, 0, 1, 1}));

  // A huge error inside the box, 0.5 in every channel of the 4 open cells.
  ImageRgb ref(4, 2), test(4, 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) {
      ref.set(x, y, {1, 1, 1});
      test.set(x, y, x < 2 ? penumbra::Rgb{1000, 1000, 1000} : penumbra::Rgb{1.5, 1.5, 1.5});
    }
  const auto m = penumbra::compare_images(test, ref, &mask);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->cells, 4u);
  EXPECT_DOUBLE_EQ(m->rmse, 0.5);
  EXPECT_DOUBLE_EQ(m->max_abs, 0.5);
  EXPECT_DOUBLE_EQ(m->bias, 0.5);
  EXPECT_NEAR(m->psnr, 20 * std::log10(1 / 0.5), 1e-12);
}

// ---- pictures ------------------------------------------------------------------------------

// A pixel of a picture read back from PNG, in [0, 1].
struct Px {
  float r, g, b;
};
Px pixel(const penumbra::io::RawImage& img, int x, int y) {
  const float* p = &img.pixels[(std::size_t(y) * img.width + x) * img.channels];
  return {p[0], p[1], p[2]};
}

// The centre pixel of cell (cx, cy) in panel `panel` of a picture laid out as `l`.
Px cell_pixel(const penumbra::io::RawImage& img, const penumbra::analysis::PictureLayout& l,
              int panel, int cx, int cy) {
  const int z = l.zoom.zoom;
  return pixel(img, l.panel_x[panel] + cx * z + z / 2, l.panel_y + cy * z + z / 2);
}

class ComparePictures : public ::testing::Test {
 protected:
  // Reads a picture back through PNG, as a person's viewer would.
  penumbra::io::RawImage round_trip(const ImageRgb8& p, const std::string& name) {
    const std::string path = tmp_.file(name);
    EXPECT_TRUE(penumbra::write_pictures({{path, p}}).ok());
    auto img = penumbra::io::read_image(path);
    EXPECT_TRUE(img.ok()) << img.error().message;
    EXPECT_EQ(img->width, p.width);
    EXPECT_EQ(img->height, p.height);
    EXPECT_EQ(img->channels, 3);
    return *img;
  }

  // 4x2 cells: errors +1, +0.5, 0, -1 on the top row; the bottom row left out by the mask.
  ImageRgb ref_ = image(4, 2, std::vector<float>(24, 2.0f));
  ImageRgb test_ = image(4, 2, {3, 3, 3, 2.5, 2.5, 2.5, 2, 2, 2, 1, 1, 1,  //
                                9, 9, 9, 9,   9,   9,   9, 9, 9, 9, 9, 9});
  std::vector<std::uint8_t> mask_ = {1, 1, 1, 1, 0, 0, 0, 0};
  penumbra::testing::TestDir tmp_{"compare"};
};

TEST_F(ComparePictures, HeatmapColoursTheSignedError) {
  const auto p = penumbra::error_heatmap(test_, ref_, &mask_);
  ASSERT_TRUE(p.ok()) << p.error().message;
  const auto l = penumbra::analysis::heatmap_layout(4, 2);
  EXPECT_EQ(p->width, l.width);
  EXPECT_EQ(p->height, l.height);
  EXPECT_EQ(l.zoom.zoom, 64);  // 4 cells zoomed to a 256-pixel map
  EXPECT_EQ(l.panel_w, 256);
  const auto img = round_trip(*p, "heatmap.png");

  const Px pos = cell_pixel(img, l, 0, 0, 0), half = cell_pixel(img, l, 0, 1, 0);
  const Px zero = cell_pixel(img, l, 0, 2, 0), neg = cell_pixel(img, l, 0, 3, 0);
  EXPECT_GT(pos.r, pos.b + 0.2f);  // reddish
  EXPECT_LT(pos.g, 0.1f);          // the full-scale red: S is the largest error of a *counted* cell
  EXPECT_GT(half.r, half.b + 0.2f);
  EXPECT_GT(half.g, pos.g);                                     // +S/2 is lighter than +S
  EXPECT_GT(neg.b, neg.r + 0.2f);                               // bluish
  for (float v : {zero.r, zero.g, zero.b}) EXPECT_GT(v, 0.9f);  // white-ish
  for (int x = 0; x < 4; ++x) {                                 // left out: mid grey
    const Px grey = cell_pixel(img, l, 0, x, 1);
    for (float v : {grey.r, grey.g, grey.b}) EXPECT_NEAR(v, 128 / 255.0f, 1e-3f);
  }
  // The colour bar runs from red at the top to blue at the bottom.
  const Px top = pixel(img, l.bar_x + 2, l.panel_y + 1);
  const Px bottom = pixel(img, l.bar_x + 2, l.panel_y + l.bar_h - 2);
  EXPECT_GT(top.r, top.b + 0.2f);
  EXPECT_GT(bottom.b, bottom.r + 0.2f);
}

// One cell far off (a light's rim, say) no longer takes the whole scale: by default S is the 99th
// percentile of the cells' |error|, so the many small errors show in colour and the one large
// error saturates; a given scale is used as it is; a bad one is refused.
TEST_F(ComparePictures, HeatmapScaleIsRobustOrGiven) {
  std::vector<float> t(200 * 3, 2.1f);  // 200 cells of error +0.1
  t[0] = t[1] = t[2] = 102;             // one of +100
  const ImageRgb test = image(20, 10, t), ref = image(20, 10, std::vector<float>(600, 2.0f));
  const auto l = penumbra::analysis::heatmap_layout(20, 10);
  const auto robust = round_trip(*penumbra::error_heatmap(test, ref), "robust.png");
  const Px small = cell_pixel(robust, l, 0, 5, 5), big = cell_pixel(robust, l, 0, 0, 0);
  EXPECT_LT(small.g, 0.1f) << "the small errors take the full red";
  EXPECT_LT(big.g, 0.1f);
  const auto given = round_trip(*penumbra::error_heatmap(test, ref, nullptr, {100.0}), "given.png");
  EXPECT_GT(cell_pixel(given, l, 0, 5, 5).g, 0.9f) << "0.1 of 100 is nearly white";
  EXPECT_LT(cell_pixel(given, l, 0, 0, 0).g, 0.1f);
  for (double bad : {-1.0, std::numeric_limits<double>::infinity()})
    EXPECT_FALSE(penumbra::error_heatmap(test, ref, nullptr, {bad}).ok()) << bad;
}

TEST_F(ComparePictures, DivergingMapIsSymmetricAroundWhite) {
  using penumbra::analysis::diverging;
  const auto white = diverging(0);
  for (unsigned char v : white) EXPECT_GE(v, 240);
  EXPECT_GT(diverging(1)[0], diverging(1)[2]);
  EXPECT_GT(diverging(-1)[2], diverging(-1)[0]);
  EXPECT_EQ(diverging(7), diverging(1));  // clamped
  EXPECT_EQ(diverging(std::numeric_limits<double>::quiet_NaN()), diverging(-1));
}

TEST_F(ComparePictures, MontageShowsBothImagesToneMappedAlike) {
  penumbra::flatland::MontageOptions o;
  o.test_label = "test: a.pfm";
  o.reference_label = "reference: b.pfm";
  o.display.exposure = 1.5f;
  const auto p = penumbra::flatland::comparison_montage(test_, ref_, &mask_, o);
  ASSERT_TRUE(p.ok()) << p.error().message;
  const auto l = penumbra::analysis::montage_layout(4, 2);
  EXPECT_EQ(p->width, l.width);
  EXPECT_EQ(p->height, l.height);
  EXPECT_EQ(l.panel_w, 256);
  EXPECT_GT(l.width, 3 * 256);
  const auto img = round_trip(*p, "montage.png");

  // Each panel shows what write_image's PNG would, at the same exposure.
  const std::vector<unsigned char> shown_test =
      penumbra::flatland::display_picture(test_, nullptr, o.display).rgb;
  const std::vector<unsigned char> shown_ref =
      penumbra::flatland::display_picture(ref_, nullptr, o.display).rgb;
  for (int x = 0; x < 4; ++x) {
    EXPECT_NEAR(cell_pixel(img, l, 0, x, 0).g, shown_test[x * 3 + 1] / 255.0f, 1e-3f) << x;
    EXPECT_NEAR(cell_pixel(img, l, 1, x, 0).g, shown_ref[x * 3 + 1] / 255.0f, 1e-3f) << x;
  }
  EXPECT_GT(cell_pixel(img, l, 0, 0, 0).g, cell_pixel(img, l, 1, 0, 0).g);  // 3 is brighter than 2
  EXPECT_GT(cell_pixel(img, l, 2, 0, 0).r, cell_pixel(img, l, 2, 0, 0).b);  // error panel: +S red

  // Text is drawn: the label row and the metrics rows hold dark pixels.
  auto dark_in_rows = [&](int y0, int y1) {
    int n = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < img.width; ++x) n += pixel(img, x, y).g < 0.3f;
    return n;
  };
  EXPECT_GT(dark_in_rows(0, l.panel_y - 1), 50);
  EXPECT_GT(dark_in_rows(l.metrics_y, l.height), 200);
}

TEST_F(ComparePictures, MontageRefusesASceneOfAnotherSize) {
  const penumbra::flatland::Scene scene = boxed_scene();  // 4x2
  penumbra::flatland::MontageOptions o;
  o.scene = &scene;
  EXPECT_TRUE(penumbra::flatland::comparison_montage(test_, ref_, &mask_, o).ok());
  const ImageRgb small = image(2, 1, {1, 1, 1, 1, 1, 1});
  const auto bad = penumbra::flatland::comparison_montage(small, small, nullptr, o);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("4x2"), std::string::npos) << bad.error().message;
}

TEST(ComparePictureLayout, LargeImagesStayOneToOneOrShrinkToFit) {
  const auto mid = penumbra::analysis::montage_layout(1000, 500);
  EXPECT_EQ(mid.zoom.zoom, 1);
  EXPECT_EQ(mid.zoom.shrink, 1);
  EXPECT_EQ(mid.panel_w, 1000);
  // Three 16384-wide panels cannot fit in a PNG this project writes: shrunk by an integer factor.
  const auto big = penumbra::analysis::montage_layout(16384, 16384);
  EXPECT_GT(big.zoom.shrink, 1);
  EXPECT_LE(big.width, penumbra::flatland::kMaxGridSide);
  EXPECT_LE(big.height, penumbra::flatland::kMaxGridSide);
  // A narrow, very tall image is zoomed only as far as the height allows.
  const auto tall = penumbra::analysis::heatmap_layout(2, 10000);
  EXPECT_EQ(tall.zoom.zoom, 1);
  EXPECT_LE(tall.height, penumbra::flatland::kMaxGridSide);
}

TEST_F(ComparePictures, ShrunkMontageIsStillMadeAndWritten) {
  // A 16384x1 image needs shrinking for the montage; the picture must still be made and written.
  ImageRgb wide(16384, 1), wide_ref(16384, 1);
  for (int x = 0; x < 16384; ++x) {
    wide.set(x, 0, {1, 1, 1});
    wide_ref.set(x, 0, {x % 2 ? 1.0f : 0.5f, 1, 1});
  }
  const auto p = penumbra::flatland::comparison_montage(wide, wide_ref);
  ASSERT_TRUE(p.ok()) << p.error().message;
  const auto l = penumbra::analysis::montage_layout(16384, 1);
  EXPECT_GT(l.zoom.shrink, 1);
  EXPECT_EQ(p->width, l.width);
  round_trip(*p, "wide.png");
}

// ---- the command line ----------------------------------------------------------------------

class CompareCli : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(tmp_.root() / "out");
    // 6x4 images: the reference a ramp, the test the ramp plus a pattern of signed errors.
    ImageRgb ref(6, 4), test(6, 4);
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 6; ++x) {
        const float v = 0.5f + 0.25f * x + 0.1f * y;
        const float e = ((x + y) % 3 - 1) * 0.05f * (1 + x);
        ref.set(x, y, {v, 2 * v, 0.5f * v});
        test.set(x, y, {v + e, 2 * v - e, 0.5f * v + 2 * e});
      }
    ref_img_ = ref;
    test_img_ = test;
    ASSERT_TRUE(penumbra::io::write_pfm(test_pfm_, test).ok());
    ASSERT_TRUE(penumbra::io::write_exr(ref_exr_, ref).ok());
    // An opaque 2x2 box in the 6x4 grid's left half.
    scene_ = tmp_.write("scene.json", R"({"penumbra": 1, "width": 6, "height": 4,
      "shapes": [{"type": "box", "center": [2, 2], "size": [2, 2]}]})");
  }

  penumbra::testing::CliResult run(const std::vector<std::string>& args) const {
    std::vector<std::string> all = {"compare"};
    all.insert(all.end(), args.begin(), args.end());
    return penumbra::testing::run_cli(all, tmp_.root());
  }
  std::string out(const std::string& name) const { return tmp_.file("out/" + name); }

  // A failure: the exit code, a message naming `names`, and nothing written to out/.
  void expect_failure(const penumbra::testing::CliResult& r, int status,
                      const std::vector<std::string>& names) const {
    EXPECT_EQ(r.status, status) << "stdout: " << r.out << "\nstderr: " << r.err;
    EXPECT_FALSE(r.err.empty());
    // Our own messages (not CLI11's parse errors) start with the command's name.
    if (!names.empty()) {
      EXPECT_EQ(r.err.rfind("penumbra compare: ", 0), 0u) << r.err;
    }
    for (const std::string& n : names) EXPECT_NE(r.err.find(n), std::string::npos) << r.err;
    EXPECT_TRUE(tmp_.entries("out").empty())
        << "left behind: " << ::testing::PrintToString(tmp_.entries("out"));
  }

  penumbra::testing::TestDir tmp_{"compare_cli"};
  std::string test_pfm_ = tmp_.file("test.pfm"), ref_exr_ = tmp_.file("ref.exr"), scene_;
  ImageRgb test_img_, ref_img_;
};

TEST_F(CompareCli, JsonMatchesTheLibrary) {
  const auto r = run({test_pfm_, ref_exr_, "--scene", scene_, "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  nlohmann::json j;
  ASSERT_NO_THROW(j = nlohmann::json::parse(r.out)) << r.out;

  auto scene = penumbra::flatland::build_scene(*penumbra::flatland::load_scene(scene_));
  ASSERT_TRUE(scene.ok());
  const std::vector<std::uint8_t> mask = penumbra::flatland::non_opaque_cells(*scene);
  const auto m = penumbra::compare_images(test_img_, ref_img_, &mask);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->cells, 20u);  // 24 cells less the 2x2 box
  EXPECT_EQ(j.at("test"), test_pfm_);
  EXPECT_EQ(j.at("reference"), ref_exr_);
  EXPECT_EQ(j.at("scene"), scene_);
  EXPECT_EQ(j.at("cells").get<std::uint64_t>(), m->cells);
  // JSON numbers round-trip doubles exactly.
  EXPECT_EQ(j.at("rmse").get<double>(), m->rmse);
  EXPECT_EQ(j.at("relative_rmse").get<double>(), m->relative_rmse);
  EXPECT_EQ(j.at("mean_abs").get<double>(), m->mean_abs);
  EXPECT_EQ(j.at("max_abs").get<double>(), m->max_abs);
  EXPECT_EQ(j.at("psnr").get<double>(), m->psnr);
  EXPECT_EQ(j.at("psnr_peak").get<double>(), m->psnr_peak);
  EXPECT_EQ(j.at("bias").get<double>(), m->bias);
  EXPECT_EQ(j.at("reference_mean").get<double>(), m->reference_mean);
  EXPECT_GT(m->rmse, 0.01);  // the inputs do differ
}

// The images' reading is refused from their headers past half of --max-memory (7 floats a
// pixel: 6x4 pixels take 672 bytes); two 16384^2 PFMs ended in bad_alloc at 5.1 GiB.
TEST_F(CompareCli, ImagesPastTheMemoryLimitAreRefusedFromTheirHeaders) {
  expect_failure(run({test_pfm_, ref_exr_, "--max-memory", "1000"}), 1,
                 {"test.pfm: reading the 6x4 image takes 672 bytes (0.0 MiB), more than its "
                  "share of --max-memory (half), 500 bytes (0.0 MiB)"});
  EXPECT_EQ(run({test_pfm_, ref_exr_, "--max-memory", "1344", "-q"}).status, 0);
  expect_failure(run({test_pfm_, ref_exr_, "--max-memory", "0.5"}), 2,
                 {"--max-memory: expected a size"});
}

TEST_F(CompareCli, WithoutASceneEveryCellCounts) {
  const auto r = run({test_pfm_, ref_exr_, "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("cells"), 24);
  EXPECT_TRUE(j.at("scene").is_null());
}

TEST_F(CompareCli, IdenticalImagesReportNullPsnr) {
  const auto r = run({test_pfm_, test_pfm_, "--json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("rmse").get<double>(), 0.0);
  EXPECT_TRUE(j.at("psnr").is_null());  // infinite: JSON has no infinity
  EXPECT_EQ(j.at("relative_rmse").get<double>(), 0.0);
}

TEST_F(CompareCli, TableByDefaultAndNothingWhenQuiet) {
  const auto r = run({test_pfm_, ref_exr_});
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* word : {"RMSE", "relative RMSE", "PSNR", "bias", "max |error|", "24"})
    EXPECT_NE(r.out.find(word), std::string::npos) << word << " missing from:\n" << r.out;
  const auto q = run({test_pfm_, ref_exr_, "-q"});
  EXPECT_EQ(q.status, 0) << q.err;
  EXPECT_TRUE(q.out.empty()) << q.out;
}

TEST_F(CompareCli, WritesHeatmapAndMontage) {
  const auto r = run({test_pfm_, ref_exr_, "--scene", scene_, "--heatmap", out("h.png"),
                      "--montage", out("m.png"), "--exposure", "-1", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(tmp_.entries("out").size(), 2u);  // no temporary files beside them
  const auto h = penumbra::io::read_image(out("h.png"));
  ASSERT_TRUE(h.ok()) << h.error().message;
  EXPECT_EQ(h->width, penumbra::analysis::heatmap_layout(6, 4).width);
  EXPECT_EQ(h->height, penumbra::analysis::heatmap_layout(6, 4).height);
  const auto m = penumbra::io::read_image(out("m.png"));
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->width, penumbra::analysis::montage_layout(6, 4).width);
  EXPECT_EQ(m->height, penumbra::analysis::montage_layout(6, 4).height);
}

// --crop X Y W H judges only that rectangle: the metrics are those of the cropped images (and
// the cropped scene's mask), the pictures have the crop's size, and a crop outside the images
// is refused with nothing written.
TEST_F(CompareCli, CropComparesOnlyTheRectangle) {
  const auto r = run({test_pfm_, ref_exr_, "--scene", scene_, "--crop", "1", "1", "4", "2",
                      "--json", "--heatmap", out("h.png")});
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ImageRgb t(4, 2), f(4, 2);
  std::vector<std::uint8_t> mask;
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) {
      t.set(x, y, test_img_.at(x + 1, y + 1));
      f.set(x, y, ref_img_.at(x + 1, y + 1));
      // The box covers cells 1..2 x 1..2 of the full grid.
      mask.push_back(x + 1 >= 1 && x + 1 <= 2 && y + 1 >= 1 && y + 1 <= 2 ? 0 : 1);
    }
  const auto m = penumbra::compare_images(t, f, &mask);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(j.at("cells").get<std::uint64_t>(), 4u);
  EXPECT_EQ(j.at("rmse").get<double>(), m->rmse);
  EXPECT_EQ(j.at("crop"), nlohmann::json({1, 1, 4, 2}));
  const auto h = penumbra::io::read_image(out("h.png"));
  ASSERT_TRUE(h.ok());
  EXPECT_EQ(h->width, penumbra::analysis::heatmap_layout(4, 2).width);
  fs::remove(out("h.png"));
  expect_failure(
      run({test_pfm_, ref_exr_, "--crop", "3", "0", "4", "2", "--heatmap", out("h.png")}), 1,
      {"--crop", "6x4"});
  expect_failure(run({test_pfm_, ref_exr_, "--crop", "0", "0", "0", "2"}), 1, {"--crop"});
  expect_failure(run({test_pfm_, ref_exr_, "--crop", "1", "2", "3"}), 2, {});
}

TEST_F(CompareCli, HelpListsTheOptions) {
  const auto r = run({"--help"});
  EXPECT_EQ(r.status, 0) << r.err;
  for (const char* opt : {"--scene", "--json", "--heatmap", "--montage", "--exposure", "--quiet"})
    EXPECT_NE(r.out.find(opt), std::string::npos) << opt << " missing from:\n" << r.out;
}

// ---- failures: nothing written -------------------------------------------------------------

TEST_F(CompareCli, MismatchedSizesNameBothFilesAndWriteNothing) {
  const std::string small = tmp_.file("small.pfm");
  ASSERT_TRUE(penumbra::io::write_pfm(small, image(2, 1, {1, 1, 1, 1, 1, 1})).ok());
  const auto r =
      run({small, ref_exr_, "--heatmap", out("h.png"), "--montage", out("m.png"), "--json"});
  expect_failure(r, 1, {"small.pfm", "ref.exr", "2x1", "6x4"});
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(CompareCli, PngInputIsRefused) {
  const std::string png = tmp_.file("render.png");
  ASSERT_TRUE(penumbra::io::write_png8(png, 6, 4, std::vector<unsigned char>(72, 100)).ok());
  expect_failure(run({png, ref_exr_, "--montage", out("m.png")}), 1, {"render.png", ".pfm"});
  expect_failure(run({test_pfm_, png}), 1, {"render.png", ".exr"});
}

TEST_F(CompareCli, MissingAndCorruptFilesAreNamed) {
  expect_failure(run({tmp_.file("nope.pfm"), ref_exr_, "--heatmap", out("h.png")}), 1,
                 {"nope.pfm"});
  const std::string corrupt = tmp_.write("corrupt.pfm", "PF\n6 4\n-1.0\nshort");
  expect_failure(run({test_pfm_, corrupt, "--heatmap", out("h.png")}), 1,
                 {"corrupt.pfm", "truncated"});
  const std::string junk = tmp_.write("junk.exr", "not an exr file at all");
  expect_failure(run({junk, ref_exr_}), 1, {"junk.exr"});
}

TEST_F(CompareCli, NonFiniteValueIsNamed) {
  ImageRgb bad = test_img_;
  bad.set(4, 2, {1, std::numeric_limits<float>::infinity(), 1});
  const std::string path = tmp_.file("inf.pfm");
  ASSERT_TRUE(penumbra::io::write_pfm(path, bad).ok());
  expect_failure(run({path, ref_exr_, "--heatmap", out("h.png")}), 1, {"inf.pfm", "(4, 2)"});
}

TEST_F(CompareCli, SceneOfAnotherSizeNamesItAndBothSizes) {
  const std::string big = tmp_.write("big.json", R"({"penumbra": 1, "width": 8, "height": 8})");
  expect_failure(run({test_pfm_, ref_exr_, "--scene", big, "--montage", out("m.png")}), 1,
                 {"big.json", "8x8", "6x4"});
}

TEST_F(CompareCli, BadSceneIsNamed) {
  const std::string bad = tmp_.write("bad.json", R"({"penumbra": 1, "width": 6})");
  expect_failure(run({test_pfm_, ref_exr_, "--scene", bad}), 1, {"bad.json"});
}

TEST_F(CompareCli, UsageErrorsExitTwo) {
  expect_failure(run({test_pfm_}), 2, {});  // no reference
  expect_failure(run({test_pfm_, ref_exr_, "--heatmap", out("h.exr")}), 2, {"h.exr", ".png"});
  expect_failure(run({test_pfm_, ref_exr_, "--montage", out("m.jpg"), "--heatmap", out("h.png")}),
                 2, {"m.jpg"});
  expect_failure(run({test_pfm_, ref_exr_, "--heatmap", out("x.png"), "--montage", out("x.png")}),
                 2, {"x.png"});
  // Refused by the parser (as in render and paint), so the message is CLI11's.
  const auto inf = run({test_pfm_, ref_exr_, "--exposure", "inf", "--montage", out("m.png")});
  expect_failure(inf, 2, {});
  EXPECT_NE(inf.err.find("--exposure: expected a finite number of EV"), std::string::npos)
      << inf.err;
  expect_failure(run({test_pfm_, ref_exr_, "--heatmap-scale", "-1", "--heatmap", out("h.png")}), 2,
                 {"--heatmap-scale"});
}

TEST_F(CompareCli, UnwritableOutputFailsBeforeWritingTheOther) {
  expect_failure(run({test_pfm_, ref_exr_, "--heatmap", out("h.png"), "--montage",
                      tmp_.file("out/no_such_dir/m.png")}),
                 1, {"m.png"});
}

}  // namespace
