// `penumbra paint` as a person would run it, in a window on a virtual X server (Xvfb): replays,
// screenshots, saving, recording, and what happens without a display.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "flatland/paint/canvas.hpp"
#include "io/image_io.hpp"
#include "test_support.hpp"
#include "xserver.hpp"

namespace {

namespace fs = std::filesystem;
using penumbra::testing::CliResult;
using penumbra::testing::run_cli;
using penumbra::testing::x_server;

// 128x128 cells: a light on the left, a wall right of it, and a patch of fog.
constexpr const char* kStrokes = R"({"strokes": [
  {"tool": "light", "color": [1, 0.9, 0.7], "intensity": 8, "radius": 6, "points": [[40, 64]]},
  {"tool": "wall", "color": [0.8, 0.8, 0.8], "radius": 2, "points": [[70, 30], [70, 98]]},
  {"tool": "fog", "color": [0.5, 0.5, 0.5], "opacity": 0.05, "radius": 8,
   "points": [[100, 110], [115, 120]]}
]})";

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
  // Skipped only where Xvfb is not installed; installed but failing to start is a failure.
  bool have_display() {
    if (!x_server().display().empty()) return true;
    if (x_server().installed()) ADD_FAILURE() << x_server().why();
    std::printf("skipped: %s\n", x_server().why().c_str());
    return false;
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
  r = paint_headless({"--device", "gpu", "--method", "pt"});  // the path tracer is CPU only
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("path tracer runs on the CPU only"), std::string::npos) << r.err;
  r = paint_headless({tmp_.write("two.json", R"({"penumbra": 1, "width": 8, "height": 8})"),
                      "--size", "16x16"});  // a scene file has its own grid
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("--size is for a blank canvas; "), std::string::npos) << r.err;
  r = paint_headless({"--exposure", "nan"});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("--exposure: expected a finite number of EV"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp_.file("shot.png")));
}

// The replay paints a light and a wall: the screenshot is bright near the light and dark in the
// wall's shadow; the saved painting renders to the same picture; the recording replays it.
TEST_F(PaintWindow, ReplayShowsLightAndShadowAndSavesWhatItShows) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  // At a fixed exposure, for the brightness thresholds below (the printed command carries it).
  CliResult r = paint({"--size", "128x128", "--zoom", "1", "--plain", "--exposure", "0", "--replay",
                       strokes_, "--screenshot", tmp_.file("shot.png"), "--save",
                       tmp_.file("painting.json"), "--record", tmp_.file("recorded.json")});
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

  // The painter prints the `penumbra render` command for the saved painting; it draws the same
  // pixels as the window's canvas (the method, --no-show-walls for --plain, automatic exposure
  // in both).
  const std::string lead = "  penumbra render ";
  const std::size_t at = r.out.find(lead);
  ASSERT_NE(at, std::string::npos) << r.out;
  std::istringstream words(r.out.substr(at + lead.size(), r.out.find('\n', at) - at - lead.size()));
  std::vector<std::string> args = {"render"};
  for (std::string w; words >> w;) args.push_back(w);
  ASSERT_GE(args.size(), 4u);
  EXPECT_EQ(args[1], tmp_.file("painting.json"));
  EXPECT_EQ(args[2], "--method");
  EXPECT_EQ(args[3], "hrc");
  EXPECT_NE(std::find(args.begin(), args.end(), "--no-show-walls"), args.end()) << r.out;
  ASSERT_EQ(args.back(), "out.png");
  args.back() = tmp_.file("render.png");
  args.push_back("-q");
  r = run_cli(args, tmp_.root());
  ASSERT_EQ(r.status, 0) << r.err;
  const penumbra::io::RawImage rendered = read_png("render.png");
  ASSERT_EQ(rendered.width, 128);
  int differing = 0;
  std::string first;  // the first difference, for the failure's message
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x)
      for (int c = 0; c < 3; ++c) {
        const float want = shot.pixels[(std::size_t(y) * shot.width + x) * shot.channels + c];
        const float got = rendered.pixels[(std::size_t(y) * 128 + x) * 3 + c];
        if (got == want) continue;
        if (differing++ == 0) {
          std::ostringstream at;
          at << "(" << x << ", " << y << ") channel " << c << ": " << got << " against " << want;
          first = at.str();
        }
      }
  EXPECT_EQ(differing, 0) << "first at " << first;

  // The recording holds the strokes replayed; replaying it paints the same canvas.
  penumbra::Expected<penumbra::flatland::paint::StrokeFile> rec =
      penumbra::flatland::paint::load_strokes(tmp_.file("recorded.json"));
  ASSERT_TRUE(rec.ok()) << rec.error().message;
  ASSERT_EQ(rec->strokes.size(), 3u);
  EXPECT_EQ(rec->strokes[1].brush.tool, penumbra::flatland::paint::Tool::wall);
  EXPECT_EQ(rec->strokes[1].points.size(), 2u);
  EXPECT_EQ(rec->width, 128);
  r = paint({"--size", "128x128", "--zoom", "1", "--plain", "--exposure", "0", "--replay",
             tmp_.file("recorded.json"), "--screenshot", tmp_.file("again.png")});
  ASSERT_EQ(r.status, 0) << r.err;
  const penumbra::io::RawImage again = read_png("again.png");
  // The window shows walls dimly where no light reaches them, unless --plain.
  r = paint({"--size", "128x128", "--zoom", "1", "--exposure", "0", "--replay", strokes_,
             "--screenshot", tmp_.file("overlay.png")});
  ASSERT_EQ(r.status, 0) << r.err;
  const penumbra::io::RawImage overlay = read_png("overlay.png");
  EXPECT_LT(grey(shot, 70, 64), 0.05f);  // the wall, as `penumbra render` shows it
  EXPECT_GT(grey(overlay, 70, 64), 0.2f);
  EXPECT_EQ(grey(overlay, 40, 114), open);  // lit cells are left alone

  ASSERT_EQ(again.width, shot.width);
  differing = 0;
  first.clear();
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128 * 3; ++x) {
      const std::size_t k = std::size_t(y) * std::size_t(shot.width) * 3 + std::size_t(x);
      if (again.pixels[k] == shot.pixels[k]) continue;
      if (differing++ == 0) {
        std::ostringstream at;
        at << "(" << x / 3 << ", " << y << ")";
        first = at.str();
      }
    }
  EXPECT_EQ(differing, 0) << "first at " << first;
}

// The painter on the GPU (lavapipe in CI), RC and HRC: the canvas is the CPU's to within one
// 8-bit step.
TEST_F(PaintWindow, GpuCanvasMatchesTheCpu) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  for (const char* method : {"rc", "hrc"}) {
    std::vector<penumbra::io::RawImage> shots;
    for (const char* device : {"cpu", "gpu"}) {
      const std::string name = std::string(method) + "_" + device + ".png";
      CliResult r = paint({"--size", "128x128", "--zoom", "1", "--plain", "--exposure", "0",
                           "--method", method, "--device", device, "--replay", strokes_,
                           "--screenshot", tmp_.file(name)});
      ASSERT_EQ(r.status, 0) << r.err;
      shots.push_back(read_png(name));
    }
    ASSERT_EQ(shots[0].width, shots[1].width);
    int worst = 0;
    for (int y = 0; y < 128; ++y)
      for (int x = 0; x < 128 * 3; ++x) {
        const std::size_t i = std::size_t(y) * shots[0].width * 3 + x;
        worst = std::max(worst, std::abs(int(shots[0].pixels[i]) - int(shots[1].pixels[i])));
      }
    EXPECT_LE(worst, 1) << method;
    EXPECT_GT(grey(shots[1], 52, 64), 0.8f) << method;  // the light is there
  }
}

// A canvas far brighter than half precision holds (the painter holds up to 1e30) renders in f16:
// the dispatcher scales its light down and the result back (HRC in f16 used to refuse it).
TEST_F(PaintWindow, BrightCanvasRendersInHalfPrecision) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  const std::string bright = tmp_.write(
      "bright.json", R"({"penumbra": 1, "width": 32, "height": 32, "shapes": [{"type": "circle",
          "center": [16, 16], "radius": 3, "emission": [1e29, 1e29, 1e29]}]})");
  CliResult r = paint({bright, "--method", "hrc", "--storage", "f16", "--zoom", "1", "--plain",
                       "--screenshot", tmp_.file("shot.png")});
  ASSERT_EQ(r.status, 0) << r.err;
  const penumbra::io::RawImage shot = read_png("shot.png");
  EXPECT_GT(grey(shot, 16, 16), 0.8f);  // the light shows
}

// Outputs that would overwrite each other, or that cannot be written, are refused before the
// window opens, and nothing is written.
TEST_F(PaintWindow, ConflictingOrUnwritableOutputsAreRefusedUpFront) {
  CliResult r = paint_headless(
      {"--size", "32x32", "--save", tmp_.file("q.json"), "--record", tmp_.file("q.json")});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("--save and --record would both write"), std::string::npos) << r.err;
  r = paint_headless({"--size", "32x32", "--save", tmp_.file("x.json"), "--screenshot",
                      tmp_.file("x.albedo.png")});
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("would both write"), std::string::npos) << r.err;
  fs::create_directories(tmp_.root() / "p.albedo.png");
  r = paint_headless(
      {"--size", "32x32", "--save", tmp_.file("p.json"), "--screenshot", tmp_.file("shot.png")});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("p.albedo.png"), std::string::npos) << r.err;
  r = paint_headless({"--size", "32x32", "--save", tmp_.file("p.txt")});
  EXPECT_EQ(r.status, 2) << r.err;
  for (const char* f : {"q.json", "x.json", "x.albedo.png", "p.json", "shot.png", "p.txt"})
    EXPECT_FALSE(fs::exists(tmp_.file(f))) << f;
}

// The window driven by a (virtual) mouse and keyboard: two strokes, Ctrl-Z (a tap shorter than a
// frame) takes the second back,
// Ctrl-Q quits; the recording and the saved painting hold the first stroke only.
TEST_F(PaintWindow, MouseStrokesUndoAndQuit) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  if (std::system("command -v xdotool >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "xdotool is not installed (scripts/install-deps.sh installs it)";
  using penumbra::testing::quote;
  const std::string script =
      "export DISPLAY=" + x_server().display() + "\n" + quote(PENUMBRA_CLI) +
      " paint --size 64x64 --zoom 4 --record " + quote(tmp_.file("rec.json")) + " --save " +
      quote(tmp_.file("out.json")) + " >" + quote(tmp_.file("paint.out")) + " 2>&1 &\n" +
      "pid=$!\n"
      "wid=$(timeout 30 xdotool search --sync --onlyvisible --name 'Penumbra painter' | head -1)\n"
      "[ -n \"$wid\" ] || { kill $pid; exit 90; }\n"
      "sleep 1\n"
      "stroke() { xdotool mousemove --window $wid $1 $2; sleep 0.3; xdotool mousedown 1; "
      "sleep 0.3; xdotool mousemove --window $wid $3 $4; sleep 0.3; xdotool mousemove --window "
      "$wid $5 $6; sleep 0.3; xdotool mouseup 1; sleep 0.5; }\n"
      "stroke 40 40 120 40 200 40\n"
      "stroke 40 200 120 200 200 200\n"
      "xdotool key --delay 0 ctrl+z; sleep 0.5\n"
      "xdotool key --delay 0 ctrl+q\n"
      "for i in $(seq 100); do kill -0 $pid 2>/dev/null || break; sleep 0.1; done\n"
      "kill -0 $pid 2>/dev/null && { kill $pid; exit 91; }\n"
      "wait $pid\n";
  const std::string file = tmp_.write("drive.sh", script);
  const int raw = std::system(("bash " + quote(file)).c_str());
  const int status = raw != -1 && WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  ASSERT_EQ(status, 0) << "painter: " << penumbra::testing::slurp(tmp_.file("paint.out"));

  penumbra::Expected<penumbra::flatland::paint::StrokeFile> rec =
      penumbra::flatland::paint::load_strokes(tmp_.file("rec.json"));
  ASSERT_TRUE(rec.ok()) << rec.error().message;
  ASSERT_EQ(rec->strokes.size(), 1u);
  EXPECT_EQ(rec->strokes[0].brush.tool, penumbra::flatland::paint::Tool::light);
  EXPECT_GE(rec->strokes[0].points.size(), 2u);
  penumbra::Expected<penumbra::flatland::SceneDesc> saved =
      penumbra::flatland::load_scene(tmp_.file("out.json"));
  ASSERT_TRUE(saved.ok()) << saved.error().message;
  const penumbra::flatland::Scene scene = penumbra::testing::build_valid(*saved);
  EXPECT_EQ(scene.opacity[scene.index(30, 10)], 1.0f);  // the first stroke, window y 40
  EXPECT_EQ(scene.opacity[scene.index(30, 50)], 0.0f);  // the second, taken back
}

// A scene file opens in the painter; measurement runs solve continuously and report times.
// Ctrl-C (SIGINT) ends a session as closing the window does: a painting session writes its
// --save and exits 130; a measurement run that has not reached its frames fails, writing nothing.
TEST_F(PaintWindow, InterruptWritesASessionButFailsAMeasurement) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  using penumbra::testing::quote;
  auto interrupted = [&](const std::string& args) {
    const std::string script = "export DISPLAY=" + x_server().display() + "\n" +
                               quote(PENUMBRA_CLI) + " paint --size 64x64 " + args + " >" +
                               quote(tmp_.file("paint.out")) + " 2>&1 &\npid=$!\nsleep 2\n" +
                               penumbra::testing::interrupt_once_caught() + "\nwait $pid\n";
    const int raw = std::system(("bash -c " + quote(script)).c_str());
    return raw != -1 && WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  };
  EXPECT_EQ(interrupted("--replay " + quote(strokes_) + " --save " + quote(tmp_.file("s.json"))),
            130)
      << penumbra::testing::slurp(tmp_.file("paint.out"));
  EXPECT_TRUE(penumbra::flatland::load_scene(tmp_.file("s.json")).ok());
  EXPECT_EQ(interrupted("--frames 1000000 --save " + quote(tmp_.file("m.json"))), 1)
      << penumbra::testing::slurp(tmp_.file("paint.out"));
  EXPECT_NE(penumbra::testing::slurp(tmp_.file("paint.out")).find("interrupted after"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(tmp_.file("m.json")));
}

// A scene file opens in the painter as `penumbra render` draws it (to the 16-bit codes of the
// painter's layers); measurement runs solve continuously and report times.
TEST_F(PaintWindow, LoadsASceneFileAndReportsFrameTimes) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  const std::string scene = PENUMBRA_SOURCE_DIR "/scenes/occluder.json";
  CliResult r = paint({scene, "--zoom", "1", "--plain", "--frames", "3", "--stats", "--screenshot",
                       tmp_.file("occluder.png")});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("method hrc, 3 solver frames"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("merge down R"), std::string::npos) << r.out;
  const penumbra::io::RawImage shot = read_png("occluder.png");
  r = run_cli(
      {"render", scene, "--method", "hrc", "--no-show-walls", "-o", tmp_.file("render.png"), "-q"},
      tmp_.root());
  ASSERT_EQ(r.status, 0) << r.err;
  const penumbra::io::RawImage rendered = read_png("render.png");
  ASSERT_GE(shot.width, rendered.width);
  ASSERT_GE(shot.height, rendered.height);
  double sum = 0, worst = 0;
  for (int y = 0; y < rendered.height; ++y)
    for (int x = 0; x < rendered.width * 3; ++x) {
      const double d = std::fabs(rendered.pixels[std::size_t(y) * rendered.width * 3 + x] -
                                 shot.pixels[std::size_t(y) * shot.width * 3 + x]);
      sum += d;
      worst = std::max(worst, d);
    }
  EXPECT_LT(sum / (rendered.width * rendered.height * 3.0), 0.1 / 255);
  EXPECT_LE(worst, 2.5 / 255);
}

}  // namespace
