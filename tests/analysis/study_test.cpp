// The quality study: its arithmetic on made-up rows, and the command end to end on a small scene.
#include "analysis/study.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "io/image_io.hpp"
#include "test_support.hpp"

namespace penumbra::flatland {
namespace {

namespace fs = std::filesystem;

study::Row row(const std::string& curve, std::uint64_t spp, double ms, double rel) {
  study::Row r;
  r.label = curve + " " + std::to_string(spp);
  r.curve = curve;
  r.samples = spp;
  r.time_ms = ms;
  r.error.relative_rmse = rel;
  return r;
}

// A curve with error exactly 1/sqrt(spp) and time proportional to spp.
std::vector<study::Row> ideal_curve() {
  std::vector<study::Row> rows;
  for (int spp : {1, 4, 16, 64}) rows.push_back(row("pt nee", spp, 10.0 * spp, 1 / std::sqrt(spp)));
  return rows;
}

TEST(Study, EqualErrorTimeInterpolatesInLogLog) {
  const std::vector<study::Row> curve = ideal_curve();
  bool extrapolated = true;
  // Error 1/sqrt(8) lies between 4 and 16 spp: time 80 ms exactly on a power law.
  EXPECT_NEAR(study::equal_error_time(curve, 1 / std::sqrt(8.0), extrapolated), 80.0, 1e-9);
  EXPECT_FALSE(extrapolated);
  // Beyond the curve: extrapolated along the last segment (1/sqrt(256) -> 2560 ms).
  EXPECT_NEAR(study::equal_error_time(curve, 1 / 16.0, extrapolated), 2560.0, 1e-6);
  EXPECT_TRUE(extrapolated);
  EXPECT_NEAR(study::equal_error_time(curve, 2.0, extrapolated), 2.5, 1e-9);
  EXPECT_TRUE(extrapolated);
  EXPECT_TRUE(std::isnan(study::equal_error_time({curve[0]}, 0.5, extrapolated)));
}

TEST(Study, ConvergenceOrderAndEqualTimes) {
  std::vector<study::Row> rows = ideal_curve();
  for (int spp : {1, 4, 16}) rows.push_back(row("pt", spp, 5.0 * spp, 2 / std::pow(spp, 0.75)));
  EXPECT_NEAR(study::convergence_order(rows, "pt nee"), 0.5, 1e-9);
  EXPECT_NEAR(study::convergence_order(rows, "pt"), 0.75, 1e-9);
  rows.push_back(row("", 0, 40.0, 1 / std::sqrt(32.0)));  // a cascade point
  study::add_equal_error_times(rows);
  EXPECT_NEAR(rows.back().pt_equal_time_ms, 320.0, 1e-6);  // 8x faster than the path tracer
  const std::string md = study::to_markdown(rows, "s.json", {"ref.pfm", 1024, 0, 0.001});
  EXPECT_NE(md.find("| 40 | 17.7% |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 320 | 8x |"), std::string::npos) << md;
  EXPECT_NE(md.find("k = 0.75 plain, 0.50 with NEE"), std::string::npos) << md;
  const std::string csv = study::to_csv(rows);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), std::ptrdiff_t(rows.size() + 1));
  const std::string svg = study::to_svg(rows, "t");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_EQ(std::count(svg.begin(), svg.end(), '\n') > 10, true);
  const ImageRgb8 png = study::to_png_plot(rows, "t");
  EXPECT_GT(png.width, 0);
  EXPECT_EQ(png.rgb.size(), std::size_t(png.width) * png.height * 3);
}

TEST(Study, SpliceSectionReplacesOnlyBetweenItsMarkers) {
  const std::string doc =
      "# Q\n<!-- bench-quality a -->\nold a\n<!-- /bench-quality a -->\n"
      "<!-- bench-quality b -->\nold b\n<!-- /bench-quality b -->\ntail\n";
  Expected<std::string> s = study::splice_section(doc, "a", "new a");
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(*s,
            "# Q\n<!-- bench-quality a -->\nnew a\n<!-- /bench-quality a -->\n"
            "<!-- bench-quality b -->\nold b\n<!-- /bench-quality b -->\ntail\n");
  // Splicing the same body again changes nothing.
  EXPECT_EQ(*study::splice_section(*s, "a", "new a\n"), *s);
  Expected<std::string> missing = study::splice_section(doc, "c", "x");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("<!-- bench-quality c -->"), std::string::npos);
  Expected<std::string> unclosed = study::splice_section("<!-- bench-quality a -->\n", "a", "x");
  ASSERT_FALSE(unclosed);
  EXPECT_NE(unclosed.error().message.find("<!-- /bench-quality a -->"), std::string::npos);
  EXPECT_FALSE(study::splice_section(doc + doc, "a", "x"));  // ambiguous: two sections
}

TEST(Study, SceneHashSeesEveryLayer) {
  SceneDesc d;
  d.width = 8;
  d.height = 6;
  Scene a = *build_scene(d);
  const std::uint64_t h = study::scene_hash(a);
  Scene b = a;
  b.albedo[5] = 0.5f;
  Scene c = a;
  c.environment.g = 1;
  EXPECT_NE(study::scene_hash(b), h);
  EXPECT_NE(study::scene_hash(c), h);
  EXPECT_EQ(study::scene_hash(a), h);
}

TEST(Study, CommandWritesEverythingAndReusesTheReference) {
  testing::TestDir dir("study");
  const std::string scene = dir.write("s.json", R"({
    "penumbra": 1, "width": 40, "height": 30, "environment": [0.02, 0.02, 0.03],
    "shapes": [ { "type": "circle", "center": [10, 15], "radius": 3, "emission": [4, 3, 2] },
                { "type": "box", "center": [22, 15], "size": [2, 12] } ] })");
  const std::string out = dir.file("q");
  const std::vector<std::string> args = {"bench-quality",   scene, "-o", out, "--quick",
                                         "--reference-spp", "64"};
  testing::CliResult r = testing::run_cli(args, dir.root());
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* f : {"quality.csv", "quality.md", "quality.svg", "quality.png",
                        "rc_vs_reference.png", "hrc_vs_reference.png"})
    EXPECT_TRUE(fs::is_regular_file(fs::path(out) / f)) << f;
  EXPECT_NE(r.out.find("rendering 64 spp"), std::string::npos) << r.out;
  const std::string md = testing::slurp(fs::path(out) / "quality.md");
  EXPECT_NE(md.find("| rc (defaults) |"), std::string::npos) << md;
  EXPECT_NE(md.find("| hrc (defaults) |"), std::string::npos) << md;
  // The cached reference is reused and gives the same table.
  r = testing::run_cli(args, dir.root());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("(cached)"), std::string::npos) << r.out;
  // --doc: the table and the pictures' links go between the scene's markers, relative to the
  // document; the rest of the document is kept.
  fs::create_directories(dir.file("docs"));
  const std::string doc = dir.write("docs/Q.md",
                                    "head\n<!-- bench-quality s -->\nold\n"
                                    "<!-- /bench-quality s -->\nfoot\n");
  std::vector<std::string> with_doc = args;
  with_doc.insert(with_doc.end(), {"--doc", doc});
  r = testing::run_cli(with_doc, dir.root());
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string updated = testing::slurp(doc);
  EXPECT_EQ(updated.rfind("head\n<!-- bench-quality s -->\nScene `", 0), 0u) << updated;
  EXPECT_NE(updated.find("| rc (defaults) |"), std::string::npos) << updated;
  EXPECT_NE(updated.find("](../q/quality.png)"), std::string::npos) << updated;
  EXPECT_NE(updated.find("](../q/rc_vs_reference.png)"), std::string::npos) << updated;
  EXPECT_NE(updated.find("](../q/hrc_vs_reference.png)"), std::string::npos) << updated;
  EXPECT_EQ(updated.find("old"), std::string::npos) << updated;
  EXPECT_NE(updated.find("<!-- /bench-quality s -->\nfoot\n"), std::string::npos) << updated;
  // A document without the scene's markers is refused before any rendering, and kept as it is.
  const std::string other = dir.write("other.md", "no markers\n");
  with_doc.back() = other;
  r = testing::run_cli(with_doc, dir.root());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("other.md"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("<!-- bench-quality s -->"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("spp"), std::string::npos) << r.out;
  EXPECT_EQ(testing::slurp(other), "no markers\n");
  // A bad scene: exit 1, the file named, nothing new written.
  const std::string bad = dir.write("bad.json", R"({"penumbra": 1, "width": -4})");
  r = testing::run_cli({"bench-quality", bad, "-o", dir.file("none")}, dir.root());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("bad.json"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir.file("none")));
}

// The same command on a 3D scene: the path tracer's curve, SPWI's and the probe grid's variants,
// every pixel counted; at two bounces, and with fog (which SPWI cannot carry).
TEST(Study, ThreeDSceneComparesSpwiAndTheGridWithThePathTracer) {
  testing::TestDir dir("study3d");
  const std::string text = R"({
    "penumbra": 1, "dimensions": 3,
    "camera": { "position": [0, 1, 3], "look_at": [0, 0, 0], "fov_y": 50, "width": 24,
                "height": 16 },
    "sky": [0.1, 0.1, 0.2],
    "materials": { "lamp": { "emission": [4, 3, 2] } },
    "objects": [ { "type": "disk", "center": [0, 0, 0], "normal": [0, 1, 0], "radius": 5 },
                 { "type": "sphere", "center": [0, 1, 0], "radius": 0.3, "material": "lamp" } ]
  })";
  const std::string scene = dir.write("s3.json", text);
  const std::string out = dir.file("q");
  const std::vector<std::string> args = {"bench-quality",   scene, "-o", out, "--max-spp", "16",
                                         "--reference-spp", "64"};
  testing::CliResult r = testing::run_cli(args, dir.root());
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* f : {"quality.csv", "quality.md", "quality.svg", "quality.png",
                        "spwi_vs_reference.png", "grid_vs_reference.png"})
    EXPECT_TRUE(fs::is_regular_file(fs::path(out) / f)) << f;
  const std::string md = testing::slurp(fs::path(out) / "quality.md");
  EXPECT_NE(md.find("64 samples per pixel"), std::string::npos) << md;
  for (const char* label :
       {"| pt 16 spp |", "| spwi (defaults) |", "| spwi --merge fix |", "| spwi t0 2x (--interval ",
        "| spwi --preaverage |", "| grid (defaults) |", "| grid voxel 0.5x (--voxel ",
        "| grid --fix bilinear |", "| grid --extend |", "| grid t0 2x (--interval "})
    EXPECT_NE(md.find(label), std::string::npos) << label << "\n" << md;
  // The path tracer's error falls with its samples (the curve the equal-error times read).
  std::vector<double> pt;
  std::istringstream csv(testing::slurp(fs::path(out) / "quality.csv"));
  for (std::string line; std::getline(csv, line);)
    if (line.rfind("\"pt ", 0) == 0) {
      std::vector<std::string> cells;
      std::stringstream cs(line);
      for (std::string c; std::getline(cs, c, ',');) cells.push_back(c);
      pt.push_back(std::stod(cells.at(6)));
    }
  ASSERT_EQ(pt.size(), 3u);
  EXPECT_GT(pt[0], 1.5 * pt[1]);
  EXPECT_GT(pt[1], 1.5 * pt[2]);
  // The reference is cached, and a changed sky needs a new one (the variants left out).
  std::vector<std::string> quick = args;
  quick.push_back("--quick");
  r = testing::run_cli(quick, dir.root());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("(cached)"), std::string::npos) << r.out;
  std::string brighter = text;
  brighter.replace(brighter.find("[0.1, 0.1, 0.2]"), 15, "[0.2, 0.1, 0.2]");
  dir.write("s3.json", brighter);
  r = testing::run_cli(quick, dir.root());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("rendering 64 spp"), std::string::npos) << r.out;
  // Two bounces: the reference and every method at two; a fog scene leaves SPWI out, said so.
  std::string foggy = text;
  foggy.replace(foggy.find("\"objects\""), 0,
                R"("media": [ { "type": "box", "center": [0, 0.5, 0], "size": [2, 1, 2],
                                "extinction": 0.5, "albedo": [0.8, 0.8, 0.8] } ],
                )");
  const std::string fog = dir.write("fog3.json", foggy);
  r = testing::run_cli({"bench-quality", fog, "-o", dir.file("b2"), "--bounces", "2", "--quick",
                        "--reference-spp", "16"},
                       dir.root());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("spwi (defaults)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("refused: spwi cannot carry fog"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("-b2-16spp.pfm"), std::string::npos) << r.out;
  // The reference has the two bounces: inside a white box lit by a lamp, its mean is the
  // two-bounce image's, not the one-bounce one's.
  const std::string box = dir.write("box3.json", R"({
    "penumbra": 1, "dimensions": 3,
    "camera": { "position": [0, 0, 0.8], "look_at": [0, -0.3, -1], "fov_y": 70, "width": 16,
                "height": 12 },
    "materials": { "white": { "albedo": [0.8, 0.8, 0.8] }, "lamp": { "emission": [5, 5, 5] } },
    "objects": [ { "type": "box", "center": [0, 0, 0], "size": [2, 2, 2], "material": "white" },
                 { "type": "sphere", "center": [0, 0.6, -0.3], "radius": 0.15,
                   "material": "lamp" } ]
  })");
  r = testing::run_cli({"bench-quality", box, "-o", dir.file("box"), "--bounces", "2", "--quick",
                        "--reference-spp", "64", "--cache", dir.file("box_cache")},
                       dir.root());
  ASSERT_EQ(r.status, 0) << r.err;
  auto mean = [](const std::string& path) {
    const Expected<ImageRgb> img = read_rgb_image(path);
    EXPECT_TRUE(img.ok()) << path;
    double sum = 0;
    for (std::size_t k = 0; img.ok() && k < img->size(); ++k) sum += img->data()[k];
    return img.ok() ? sum / double(img->size()) : 0.0;
  };
  std::string cached;
  for (const auto& f : fs::directory_iterator(dir.file("box_cache"))) cached = f.path().string();
  EXPECT_NE(cached.find("-b2-64spp.pfm"), std::string::npos) << cached;
  for (const char* b : {"1", "2"}) {
    const auto rr = testing::run_cli({"render", box, "--bounces", b, "--spp", "64", "-q", "-o",
                                      dir.file(std::string("box_b") + b + ".pfm")},
                                     dir.root());
    ASSERT_EQ(rr.status, 0) << rr.err;
  }
  const double ref = mean(cached), one = mean(dir.file("box_b1.pfm")),
               two = mean(dir.file("box_b2.pfm"));
  EXPECT_GT(two, 1.3 * one);
  EXPECT_LT(std::abs(ref - two), 0.1 * std::abs(two - one)) << ref << " " << one << " " << two;
  const std::string md2 = testing::slurp(fs::path(dir.file("b2")) / "quality.md");
  EXPECT_NE(md2.find("| grid (defaults) |"), std::string::npos) << md2;
  EXPECT_EQ(md2.find("| spwi"), std::string::npos) << md2;
  EXPECT_TRUE(fs::is_regular_file(fs::path(dir.file("b2")) / "grid_vs_reference.png"));
}

}  // namespace
}  // namespace penumbra::flatland
