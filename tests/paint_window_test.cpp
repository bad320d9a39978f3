// `penumbra paint` as a person would run it, in a window on a virtual X server (Xvfb): replays,
// screenshots, saving, recording, and what happens without a display.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "io/image_io.hpp"
#include "paint/canvas.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using penumbra::testing::CliResult;
using penumbra::testing::run_cli;

// 128x128 cells: a light on the left, a wall right of it, and a patch of fog.
constexpr const char* kStrokes = R"({"strokes": [
  {"tool": "light", "color": [1, 0.9, 0.7], "intensity": 8, "radius": 6, "points": [[40, 64]]},
  {"tool": "wall", "color": [0.8, 0.8, 0.8], "radius": 2, "points": [[70, 30], [70, 98]]},
  {"tool": "fog", "color": [0.5, 0.5, 0.5], "opacity": 0.05, "radius": 8,
   "points": [[100, 110], [115, 120]]}
]})";

// One Xvfb for the suite, on a display number no one else holds.
class XServer {
 public:
  XServer() {
    if (std::system("command -v Xvfb >/dev/null 2>&1") != 0) {
      why_ = "Xvfb is not installed (scripts/install-deps.sh installs it)";
      return;
    }
    for (int n = 100 + int(getpid() % 400); n < 1000 && display_.empty(); n += 7) {
      if (fs::exists("/tmp/.X" + std::to_string(n) + "-lock")) continue;
      const fs::path pidfile = fs::temp_directory_path() / ("penumbra_xvfb_" + std::to_string(n));
      const std::string cmd = "Xvfb :" + std::to_string(n) +
                              " -screen 0 1280x1024x24 -nolisten tcp >/dev/null 2>&1 & echo $! > " +
                              penumbra::testing::quote(pidfile.string());
      if (std::system(cmd.c_str()) != 0) continue;
      pid_ = std::atoi(penumbra::testing::slurp(pidfile).c_str());
      fs::remove(pidfile);
      const std::string socket = "/tmp/.X11-unix/X" + std::to_string(n);
      for (int tries = 0; tries < 100 && !fs::exists(socket); ++tries)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (fs::exists(socket) && pid_ > 0 && kill(pid_, 0) == 0)
        display_ = ":" + std::to_string(n);
      else
        stop();
    }
    if (display_.empty()) why_ = "no X server could be started with Xvfb";
  }
  ~XServer() { stop(); }
  const std::string& display() const { return display_; }
  const std::string& why() const { return why_; }

 private:
  void stop() {
    if (pid_ > 0) kill(pid_, SIGTERM);
    pid_ = 0;
  }
  std::string display_, why_;
  int pid_ = 0;
};

XServer& x_server() {
  static XServer server;
  return server;
}

class PaintWindow : public ::testing::Test {
 protected:
  void SetUp() override { strokes_ = tmp_.write("strokes.json", kStrokes); }

  // Runs the painter on the virtual display (skips the test when there is none).
  CliResult paint(std::vector<std::string> args) {
    args.insert(args.begin(), "paint");
    setenv("DISPLAY", x_server().display().c_str(), 1);
    unsetenv("WAYLAND_DISPLAY");
    return run_cli(args, tmp_.root());
  }
  bool have_display() {
    if (x_server().display().empty()) {
      std::printf("skipped: %s\n", x_server().why().c_str());
      return false;
    }
    return true;
  }
  CliResult paint_headless(std::vector<std::string> args) {
    args.insert(args.begin(), "paint");
    unsetenv("DISPLAY");
    unsetenv("WAYLAND_DISPLAY");
    return run_cli(args, tmp_.root());
  }

  penumbra::io::RawImage read_png(const std::string& name) {
    penumbra::Expected<penumbra::io::RawImage> img = penumbra::io::read_image(tmp_.file(name));
    EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.error().message);
    return img.ok() ? *img : penumbra::io::RawImage{};
  }

  penumbra::testing::TestDir tmp_{"paint"};
  std::string strokes_;
};

// Mean of the red, green and blue values (0..1) of pixel (x, y).
float grey(const penumbra::io::RawImage& img, int x, int y) {
  const float* p = &img.pixels[(std::size_t(y) * img.width + x) * img.channels];
  return (p[0] + p[1] + p[2]) / 3;
}

TEST_F(PaintWindow, WithoutADisplayItSaysSoAndExitsOne) {
  CliResult r = paint_headless({"--size", "32x32", "--screenshot", tmp_.file("shot.png")});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("no display"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp_.file("shot.png")));
}

// Bad input is reported before any window is opened, with the file and JSON path.
TEST_F(PaintWindow, BadInputIsReportedBeforeTheWindow) {
  const std::string bad = tmp_.write(
      "bad.json", R"({"strokes": [{"tool": "wall", "radius": -2, "points": [[1, 1]]}]})");
  CliResult r =
      paint_headless({"--size", "32x32", "--replay", bad, "--screenshot", tmp_.file("shot.png")});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("bad.json: strokes[0].radius"), std::string::npos) << r.err;
  // Too bright for the canvas's emission scale.
  const std::string bright = tmp_.write(
      "bright.json", R"({"strokes": [{"tool": "light", "intensity": 500, "points": [[1, 1]]}]})");
  r = paint_headless({"--size", "32x32", "--replay", bright});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("bright.json: strokes[0].intensity"), std::string::npos) << r.err;
  r = paint_headless({"--size", "32by32"});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("--size"), std::string::npos) << r.err;
  r = paint_headless({"--size", "5000x16"});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("4096"), std::string::npos) << r.err;
  r = paint_headless({tmp_.file("missing.json")});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("missing.json"), std::string::npos) << r.err;
  r = paint_headless({"--device", "gpu"});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_FALSE(fs::exists(tmp_.file("shot.png")));
}

// The replay paints a light and a wall: the screenshot is bright near the light and dark in the
// wall's shadow; the saved painting renders to the same picture; the recording replays it.
TEST_F(PaintWindow, ReplayShowsLightAndShadowAndSavesWhatItShows) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  CliResult r = paint({"--size", "128x128", "--zoom", "1", "--plain", "--replay", strokes_,
                       "--screenshot", tmp_.file("shot.png"), "--save", tmp_.file("painting.json"),
                       "--record", tmp_.file("recorded.json")});
  ASSERT_EQ(r.status, 0) << r.err;
  const penumbra::io::RawImage shot = read_png("shot.png");
  ASSERT_GE(shot.width, 128 + 300);  // the canvas and the panel beside it
  ASSERT_GE(shot.height, 128);
  // Light at (40, 64), radius 6; the wall is the segment x = 70, y 30..98, 4 cells wide.
  const float near = grey(shot, 52, 64);    // 12 cells right of the light
  const float open = grey(shot, 40, 114);   // 50 cells below it, in the open
  const float shadow = grey(shot, 90, 64);  // 50 cells right of it, behind the wall
  EXPECT_GT(near, 0.8f);
  EXPECT_GT(open, 0.3f);
  EXPECT_LT(shadow, 0.3f * open) << "open " << open << " shadow " << shadow;

  // `penumbra render` of the saved painting draws the same pixels as the window's canvas.
  r = run_cli({"render", tmp_.file("painting.json"), "--method", "hrc", "-o",
               tmp_.file("render.png"), "-q"},
              tmp_.root());
  ASSERT_EQ(r.status, 0) << r.err;
  const penumbra::io::RawImage rendered = read_png("render.png");
  ASSERT_EQ(rendered.width, 128);
  int differing = 0;
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x)
      for (int c = 0; c < 3; ++c)
        differing += rendered.pixels[(std::size_t(y) * 128 + x) * 3 + c] !=
                     shot.pixels[(std::size_t(y) * shot.width + x) * shot.channels + c];
  EXPECT_EQ(differing, 0);

  // The recording holds the strokes replayed; replaying it paints the same canvas.
  penumbra::Expected<std::vector<penumbra::paint::Stroke>> rec =
      penumbra::paint::load_strokes(tmp_.file("recorded.json"));
  ASSERT_TRUE(rec.ok()) << rec.error().message;
  ASSERT_EQ(rec->size(), 3u);
  EXPECT_EQ((*rec)[1].brush.tool, penumbra::paint::Tool::wall);
  EXPECT_EQ((*rec)[1].points.size(), 2u);
  r = paint({"--size", "128x128", "--zoom", "1", "--plain", "--replay", tmp_.file("recorded.json"),
             "--screenshot", tmp_.file("again.png")});
  ASSERT_EQ(r.status, 0) << r.err;
  const penumbra::io::RawImage again = read_png("again.png");
  // The window shows walls dimly where no light reaches them, unless --plain.
  r = paint({"--size", "128x128", "--zoom", "1", "--replay", strokes_, "--screenshot",
             tmp_.file("overlay.png")});
  ASSERT_EQ(r.status, 0) << r.err;
  const penumbra::io::RawImage overlay = read_png("overlay.png");
  EXPECT_LT(grey(shot, 70, 64), 0.05f);  // the wall, as `penumbra render` shows it
  EXPECT_GT(grey(overlay, 70, 64), 0.2f);
  EXPECT_EQ(grey(overlay, 40, 114), open);  // lit cells are left alone

  ASSERT_EQ(again.width, shot.width);
  differing = 0;
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128 * 3; ++x)
      differing += again.pixels[std::size_t(y) * again.width * 3 + x] !=
                   shot.pixels[std::size_t(y) * shot.width * 3 + x];
  EXPECT_EQ(differing, 0);
}

// A scripted run whose final canvas the method refuses writes nothing and exits 1.
TEST_F(PaintWindow, RefusedRenderFailsAScriptedRun) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  const std::string bright = tmp_.write(
      "bright.json", R"({"strokes": [{"tool": "light", "intensity": 1e5, "points": [[8, 8]]}]})");
  CliResult r =
      paint({"--size", "32x32", "--storage", "f16", "--emission-scale", "1e6", "--replay", bright,
             "--screenshot", tmp_.file("shot.png"), "--save", tmp_.file("p.json")});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("half precision"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp_.file("shot.png")));
  EXPECT_FALSE(fs::exists(tmp_.file("p.json")));
}

// A scene file opens in the painter; measurement runs solve continuously and report times.
TEST_F(PaintWindow, LoadsASceneFileAndReportsFrameTimes) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  CliResult r = paint({PENUMBRA_SOURCE_DIR "/scenes/occluder.json", "--zoom", "0.5", "--frames",
                       "3", "--stats", "--screenshot", tmp_.file("occluder.png")});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("method hrc"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("solver frames"), std::string::npos) << r.out;
  const penumbra::io::RawImage shot = read_png("occluder.png");
  EXPECT_GT(shot.width, 300);
}

}  // namespace
