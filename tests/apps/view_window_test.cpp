// `penumbra view` as a person would run it, in a window on a virtual X server (Xvfb): replays,
// screenshots against the render command "Save view" prints, recordings, frame times, bad input
// and what happens without a display.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "io/image_io.hpp"
#include "penumbra/spaceland/scene.hpp"
#include "test_support.hpp"
#include "xserver.hpp"

namespace {

namespace fs = std::filesystem;
using penumbra::testing::CliResult;
using penumbra::testing::run_cli;
using penumbra::testing::x_server;

// A floor, a box and a wall under a sun and a gradient sky, and a small emitter: every method
// renders it in well under a second at the sizes below.
constexpr const char* kScene = R"({"penumbra": 1, "dimensions": 3,
  "camera": {"position": [0, 1.2, 3.5], "look_at": [0, 0.4, 0], "fov_y": 50,
             "width": 64, "height": 48},
  "sky": {"zenith": [0.3, 0.45, 0.8], "horizon": [0.7, 0.75, 0.8], "ground": [0.2, 0.2, 0.2]},
  "sun": {"direction": [0.4, 1, 0.3], "irradiance": [3, 2.8, 2.5]},
  "materials": {"white": {"albedo": [0.75, 0.75, 0.75]},
                "red": {"albedo": [0.8, 0.2, 0.15]},
                "lamp": {"albedo": [0, 0, 0], "emission": [6, 5, 3]}},
  "objects": [
    {"type": "quad", "corner": [-3, 0, -3], "u": [0, 0, 6], "v": [6, 0, 0],
     "material": "white"},
    {"type": "box", "center": [0.4, 0.4, 0], "size": [0.8, 0.8, 0.8], "material": "red"},
    {"type": "quad", "corner": [-1.5, 0, -1], "u": [0, 1.5, 0], "v": [0, 0, 2],
     "material": "white"},
    {"type": "sphere", "center": [-0.8, 0.3, 0.8], "radius": 0.15, "material": "lamp"}
  ]})";

class ViewWindow : public ::testing::Test {
 protected:
  void SetUp() override { scene_ = tmp_.write("scene.json", kScene); }

  CliResult view(std::vector<std::string> args) {
    args.insert(args.begin(), "view");
    setenv("DISPLAY", x_server().display().c_str(), 1);
    unsetenv("WAYLAND_DISPLAY");
    return run_cli(args, tmp_.root());
  }
  CliResult view_headless(std::vector<std::string> args) {
    args.insert(args.begin(), "view");
    unsetenv("DISPLAY");
    unsetenv("WAYLAND_DISPLAY");
    return run_cli(args, tmp_.root());
  }
  bool have_display() {
    if (!x_server().display().empty()) return true;
    if (x_server().installed()) ADD_FAILURE() << x_server().why();
    std::printf("skipped: %s\n", x_server().why().c_str());
    return false;
  }
  penumbra::io::RawImage read_png(const std::string& path) {
    penumbra::Expected<penumbra::io::RawImage> img = penumbra::io::read_image(path);
    EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.error().message);
    return img.ok() ? *img : penumbra::io::RawImage{};
  }
  // The render command "Save view" printed, run with its output in the test's folder.
  CliResult run_printed(const std::string& out, const std::string& png) {
    const std::string marker = "render this view at full resolution:\n  penumbra render ";
    const std::size_t at = out.find(marker);
    EXPECT_NE(at, std::string::npos) << out;
    if (at == std::string::npos) return {};
    std::istringstream words(
        out.substr(at + marker.size(), out.find('\n', at + marker.size()) - at - marker.size()));
    std::vector<std::string> args = {"render"};
    for (std::string w; words >> w;) args.push_back(w);
    EXPECT_EQ(args.back(), "out.png");
    args.back() = png;
    args.push_back("-q");
    return run_cli(args, tmp_.root());
  }
  // The view's pixels of the screenshot (the panel is right of it) equal the PNG's, exactly.
  void expect_same_pixels(const std::string& shot_path, const std::string& png_path, int w, int h) {
    const penumbra::io::RawImage shot = read_png(shot_path), png = read_png(png_path);
    ASSERT_EQ(png.width, w);
    ASSERT_EQ(png.height, h);
    ASSERT_GE(shot.width, w + 300);
    ASSERT_GE(shot.height, h);
    int differ = 0;
    float sum = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) {
          const float a = shot.pixels[(std::size_t(y) * shot.width + x) * shot.channels + c];
          const float b = png.pixels[(std::size_t(y) * png.width + x) * png.channels + c];
          differ += a != b;
          sum += b;
        }
    EXPECT_EQ(differ, 0) << shot_path << " and " << png_path;
    EXPECT_GT(sum / float(w * h * 3), 0.05f) << "a black picture proves little";
  }

  penumbra::testing::TestDir tmp_{"view"};
  std::string scene_;
};

TEST_F(ViewWindow, WithoutADisplayItSaysSoAndExitsOne) {
  CliResult r = view_headless({scene_, "--screenshot", tmp_.file("shot.png")});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("no display"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp_.file("shot.png")));
}

// Bad input is reported before any window opens (no display is needed to see it), naming the
// file and the JSON path; nothing is written.
TEST_F(ViewWindow, BadInputIsReportedBeforeTheWindow) {
  const std::string shot = tmp_.file("shot.png");
  struct Case {
    const char* replay;
    int status;
    const char* message;
  };
  const Case cases[] = {
      {R"({"penumbra_view": 1, "events": [{"wait": {"frames": 1}}, {"set": {"bounces": 0}}]})", 1,
       "r.json: events[1].set.bounces: expected an integer in 1..64, found 0"},
      {R"({"penumbra_view": 1, "events": [{"fly": {}}]})", 1,
       "r.json: events[0]: unknown event \"fly\""},
      {R"({"penumbra_view": 1, "events": [{"set": {"colour": 1}}]})", 1,
       "r.json: events[0].set.colour: unknown setting"},
      {R"({"penumbra_view": 1, "events": [{"set": {"method": "hrc"}}]})", 1,
       "r.json: events[0].set.method: expected one of ssrc, spwi, surface, grid, pt"},
      {R"({"penumbra_view": 1, "events": [{"camera": {"position": [0, 1], "yaw": 0,
          "pitch": 0}}]})",
       1, "r.json: events[0].camera.position: expected 3 numbers"},
      {R"({"penumbra_view": 1, "events": [{"camera": {"position": [0, 1, 2], "yaw": 0,
          "pitch": 95}}]})",
       1, "r.json: events[0].camera.pitch: expected -89..89 degrees"},
      {R"({"penumbra_view": 2, "events": []})", 1, "r.json: penumbra_view"},
      {R"({"events": [}})", 1, "r.json: line 1"},
      {R"({"penumbra_view": 1, "events": [{"set": {"spwi.directions": 5}}]})", 1,
       "r.json: events[0].set: `spwi.directions`"},
  };
  for (const Case& c : cases) {
    const std::string replay = tmp_.write("r.json", c.replay);
    CliResult r = view_headless({scene_, "--replay", replay, "--screenshot", shot});
    EXPECT_EQ(r.status, c.status) << c.replay << "\n" << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.replay << "\n" << r.err;
  }
  // A scene without a sun has none to move.
  const std::string dark =
      tmp_.write("dark.json", R"({"penumbra": 1, "dimensions": 3, "camera": {"position": [0, 0, 3],
      "look_at": [0, 0, 0], "fov_y": 40, "width": 32, "height": 32}, "objects": [{"type":
      "sphere", "center": [0, 0, 0], "radius": 1}]})");
  const std::string sunny =
      tmp_.write("sun.json", R"({"penumbra_view": 1, "events": [{"set": {"sun_azimuth": 10}}]})");
  CliResult r = view_headless({dark, "--replay", sunny});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("sun.json: events[0].set.sun_azimuth: the scene has no sun to move"),
            std::string::npos)
      << r.err;
  // The options, the outputs and the scene.
  const std::vector<std::pair<std::vector<std::string>, std::string>> usage = {
      {{"--method", "hrc"}, "--method hrc: expected one of"},
      {{"--scale", "0.01"}, "--scale: expected 0 (automatic) or a scale in [1/16, 1]"},
      {{"--screenshot", tmp_.file("shot.jpg")}, "expected a .png name"},
      {{"--save", tmp_.file("view.txt")}, "expected a .json name"},
      {{"--atlas", tmp_.file("a.exr")}, "--atlas applies to --method surface only"},
      {{"--size", "64by48"}, "--size: expected WxH"},
      {{"--upscale", "nearest"}, "--upscale: nearest not in"},
      {{"--save", scene_}, "would overwrite the scene file"},
      {{"--screenshot", shot, "--record", shot}, "would both write"},
  };
  for (const auto& [args, message] : usage) {
    std::vector<std::string> a = {scene_};
    a.insert(a.end(), args.begin(), args.end());
    CliResult u = view_headless(a);
    EXPECT_EQ(u.status, 2) << message << "\n" << u.err;
    EXPECT_NE(u.err.find(message), std::string::npos) << u.err;
  }
  r = view_headless({scene_, "--max-memory", "1M"});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("needs about"), std::string::npos) << r.err;
  const std::string flat = tmp_.write("flat.json", R"({"penumbra": 1, "width": 8, "height": 8})");
  r = view_headless({flat});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("a 2D scene; the viewer flies through 3D scenes"), std::string::npos)
      << r.err;
  r = view_headless({tmp_.file("missing.json")});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("missing.json"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(shot));
  EXPECT_FALSE(fs::exists(tmp_.file("view.json")));
}

// For each method: fly (move, turn, move the sun), then the screenshot's view equals, pixel for
// pixel, what the render command that "Save view" printed draws from the saved file, at the
// view's resolution (--scale 1: no internal resolution, no upscaling).
TEST_F(ViewWindow, ScreenshotIsWhatThePrintedRenderCommandDraws) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  for (const char* method : {"ssrc", "spwi", "grid", "surface", "pt"}) {
    SCOPED_TRACE(method);
    const std::string replay =
        tmp_.write("fly.json", std::string(R"({"penumbra_view": 1, "events": [
        {"move": {"by": [0.3, 0.1, 0.8], "turn": [12, -4]}},
        {"set": {"method": ")") + method +
                                   R"(", "scale": 1, "sun_azimuth": 40, "sun_elevation": 35,
                 "surface.texels": 4096}},
        {"move": {"by": [-0.1, 0, 0.2]}},
        {"set": {"bounces": 2}}]})");
    const std::string shot = tmp_.file(std::string(method) + "_shot.png"),
                      saved = tmp_.file(std::string(method) + "_view.json");
    CliResult r = view({scene_, "--replay", replay, "--screenshot", shot, "--save", saved});
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string png = tmp_.file(std::string(method) + "_render.png");
    CliResult rendered = run_printed(r.out, png);
    ASSERT_EQ(rendered.status, 0) << rendered.err;
    expect_same_pixels(shot, png, 64, 48);
  }
}

// The grid solved a few slabs a frame: after the sun moves (with two bounces, which light the
// voxels with it), frames show the last grid while the new one is solved, and the screenshot
// waits for it: the picture is the printed render command's, which solves it whole.
TEST_F(ViewWindow, GridSlabsEndOnWhatThePrintedRenderCommandDraws) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  const std::string replay = tmp_.write("sun.json", R"({"penumbra_view": 1, "events": [
      {"set": {"bounces": 2}}, {"wait": {"frames": 2}},
      {"set": {"sun_azimuth": 40, "sun_elevation": 35}}]})");
  const std::string shot = tmp_.file("slabs_shot.png");
  CliResult r =
      view({scene_, "--method", "grid", "--scale", "1", "--grid-slabs", "2", "--replay", replay,
            "--screenshot", shot, "--save", tmp_.file("slabs_view.json"), "--stats"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string counted = "grid slabs: ";
  const std::size_t at = r.out.find(counted);
  ASSERT_NE(at, std::string::npos) << r.out;
  EXPECT_GE(std::atoi(r.out.c_str() + at + counted.size()), 1) << r.out;
  const std::string png = tmp_.file("slabs_render.png");
  CliResult rendered = run_printed(r.out, png);
  ASSERT_EQ(rendered.status, 0) << rendered.err;
  expect_same_pixels(shot, png, 64, 48);
}

// Below the view's resolution, guided upscaling (depth, normals, albedo at the view's pixels)
// is closer to the full-resolution render than bilinear filtering, and the frame is shown at the
// view's size. The surface method's pixels look up an atlas that does not depend on the camera,
// so the internal image samples the full one and the difference is the upscaling's.
TEST_F(ViewWindow, GuidedUpscalingIsCloserToTheFullRenderThanBilinear) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  CliResult full =
      run_cli({"render", scene_, "--method", "surface", "--texels", "4096", "--width", "128",
               "--height", "96", "--exposure", "0", "-o", tmp_.file("full.png"), "-q"},
              tmp_.root());
  ASSERT_EQ(full.status, 0) << full.err;
  const penumbra::io::RawImage ref = read_png(tmp_.file("full.png"));
  double error[2] = {0, 0};
  int k = 0;
  for (const char* upscale : {"guided", "bilinear"}) {
    const std::string replay =
        tmp_.write("up.json", std::string(R"({"penumbra_view": 1, "events": [{"set": {"scale": 0.25,
        "method": "surface", "surface.texels": 4096, "upscale": ")") +
                                  upscale + R"("}}]})");
    const std::string shot = tmp_.file(std::string(upscale) + ".png");
    CliResult r = view(
        {scene_, "--size", "128x96", "--exposure", "0", "--replay", replay, "--screenshot", shot});
    ASSERT_EQ(r.status, 0) << r.err;
    const penumbra::io::RawImage s = read_png(shot);
    for (int y = 0; y < 96; ++y)
      for (int x = 0; x < 128 * 3; ++x)
        error[k] += std::fabs(s.pixels[std::size_t(y) * s.width * 3 + x] -
                              ref.pixels[std::size_t(y) * 128 * 3 + x]);
    ++k;
  }
  std::printf("guided %g, bilinear %g\n", error[0], error[1]);
  EXPECT_LT(error[0], 0.3 * error[1]) << "guided " << error[0] << ", bilinear " << error[1];
}

// The recording of a session replays to the same picture; the saved view keeps its meshes when
// written to another folder.
TEST_F(ViewWindow, RecordingReplaysToTheSamePicture) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  const std::string replay = tmp_.write("fly.json", R"({"penumbra_view": 1, "events": [
      {"set": {"scale": 1, "method": "spwi"}},
      {"move": {"by": [0.2, 0, 0.5], "turn": [-20, 6]}},
      {"wait": {"frames": 2}},
      {"move": {"turn": [5, 0]}}]})");
  CliResult r = view({scene_, "--replay", replay, "--screenshot", tmp_.file("a.png"), "--record",
                      tmp_.file("rec.json")});
  ASSERT_EQ(r.status, 0) << r.err;
  r = view({scene_, "--replay", tmp_.file("rec.json"), "--screenshot", tmp_.file("b.png")});
  ASSERT_EQ(r.status, 0) << r.err;
  // The view, not the panel (its frame times differ).
  const penumbra::io::RawImage a = read_png(tmp_.file("a.png")), b = read_png(tmp_.file("b.png"));
  ASSERT_EQ(a.width, b.width);
  ASSERT_GE(a.height, 48);
  int differ = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64 * a.channels; ++x)
      differ += a.pixels[std::size_t(y) * a.width * a.channels + x] !=
                b.pixels[std::size_t(y) * b.width * b.channels + x];
  EXPECT_EQ(differ, 0);
  // The recording holds the camera the replay reached, not the replay's steps.
  const std::string recorded = penumbra::testing::slurp(tmp_.file("rec.json"));
  EXPECT_NE(recorded.find("\"camera\""), std::string::npos) << recorded;
  EXPECT_NE(recorded.find("\"yaw\": -15.0"), std::string::npos) << recorded;
}

// A view saved into another folder keeps the scene's mesh files (named relative to the scene
// file): the printed command draws the same pixels from there.
TEST_F(ViewWindow, AViewSavedElsewhereKeepsItsMeshes) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  fs::create_directories(tmp_.root() / "elsewhere");
  const std::string cornell = std::string(PENUMBRA_SOURCE_DIR) + "/scenes/3d/cornell.json";
  const std::string replay = tmp_.write("r.json", R"({"penumbra_view": 1, "events": [
      {"move": {"by": [20, 0, 100]}, "comment": "comment keys are allowed beside an event"},
      {"set": {"scale": 1}}]})");
  const std::string saved = (tmp_.root() / "elsewhere" / "view.json").string();
  CliResult r = view({cornell, "--size", "48x48", "--replay", replay, "--screenshot",
                      tmp_.file("shot.png"), "--save", saved});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(penumbra::testing::slurp(saved).find("\"cornell_box.obj\""), std::string::npos);
  const std::string png = tmp_.file("render.png");
  CliResult rendered = run_printed(r.out, png);
  ASSERT_EQ(rendered.status, 0) << rendered.err;
  expect_same_pixels(tmp_.file("shot.png"), png, 48, 48);
}

// A view the method refuses while a replay waits on it ends the run with a message (it is not
// rendered again and again).
TEST_F(ViewWindow, ARefusedViewEndsAWait) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  const std::string fog = tmp_.write("fog.json", R"({"penumbra": 1, "dimensions": 3,
    "camera": {"position": [0, 1, 3], "look_at": [0, 0.5, 0], "fov_y": 50, "width": 32,
               "height": 24},
    "sky": [1, 1, 1],
    "objects": [{"type": "quad", "corner": [-2, 0, -2], "u": [0, 0, 4], "v": [4, 0, 0]}],
    "media": [{"type": "box", "center": [0, 0.5, 0], "size": [1, 1, 1], "extinction": 0.5,
               "albedo": [0.5, 0.5, 0.5]}]})");
  const std::string replay = tmp_.write("r.json", R"({"penumbra_view": 1, "events": [
      {"set": {"method": "spwi"}}, {"wait": {"frames": 3}}]})");
  CliResult r =
      view({fog, "--method", "grid", "--replay", replay, "--screenshot", tmp_.file("shot.png")});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("spwi cannot carry fog"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("could not be rendered; nothing written"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp_.file("shot.png")));
}

// --frames renders continuously (at least N frames, the last of the view the internal
// resolution settled on) and --stats prints the frame time per stage.
TEST_F(ViewWindow, FramesPrintFrameTimesPerStage) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  CliResult r = view({scene_, "--method", "ssrc", "--frames", "4", "--stats"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::size_t at = r.out.find("method ssrc, ");
  ASSERT_NE(at, std::string::npos) << r.out;
  EXPECT_GE(std::atoi(r.out.c_str() + at + 13), 4) << r.out;
  for (const char* line : {" frames\n", "internal resolution: median", "frame (render()): median",
                           "G-buffer", "cascade 0", "gather", "tone map: median", "window: median"})
    EXPECT_NE(r.out.find(line), std::string::npos) << line << "\n" << r.out;
}

// With temporal accumulation (ssrc and spwi) a screenshot waits for the history to fill: at least
// --temporal frames of the last view, each with the "temporal" stage, and a picture other than the
// single frame's. An exposure change alone tone-maps the last picture again (no frame is rendered),
// and the picture is still the printed render command's at that exposure.
TEST_F(ViewWindow, TemporalFramesAndAnExposureChangeAlone) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  for (const std::string method : {"ssrc", "spwi"}) {
    const std::string single = tmp_.file(method + "_single.png"),
                      accumulated = tmp_.file(method + "_accumulated.png");
    CliResult r = view({scene_, "--method", method, "--scale", "1", "--screenshot", single});
    ASSERT_EQ(r.status, 0) << r.err;
    r = view({scene_, "--method", method, "--scale", "1", "--temporal", "6", "--screenshot",
              accumulated, "--stats"});
    ASSERT_EQ(r.status, 0) << r.err;
    // The screenshot waited for the history to fill: 6 frames of the still view (the window
    // shows the latest frame, so it may have drawn fewer).
    EXPECT_NE(r.out.find("the last picture is frame 6 of its history (a pixel blends at most 6)"),
              std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("    temporal "), std::string::npos) << r.out;
    const penumbra::io::RawImage a = read_png(single), b = read_png(accumulated);
    ASSERT_EQ(a.pixels.size(), b.pixels.size());
    int differ = 0;
    for (std::size_t k = 0; k < a.pixels.size(); ++k) differ += a.pixels[k] != b.pixels[k];
    EXPECT_GT(differ, 0) << method << ": the accumulated picture is the single frame's";
  }

  const std::string replay = tmp_.write("exposure.json", R"({"penumbra_view": 1, "events": [
      {"wait": {"frames": 2}}, {"set": {"exposure": 1.5}}]})");
  const std::string shot = tmp_.file("exposure_shot.png");
  CliResult r = view({scene_, "--method", "spwi", "--scale", "1", "--replay", replay,
                      "--screenshot", shot, "--save", tmp_.file("exposure_view.json"), "--stats"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("; 1 pictures tone-mapped again"), std::string::npos) << r.out;
  const std::string png = tmp_.file("exposure_render.png");
  CliResult rendered = run_printed(r.out, png);
  ASSERT_EQ(rendered.status, 0) << rendered.err;
  expect_same_pixels(shot, png, 64, 48);
}

// A person at the keyboard and mouse (xdotool): W flies forward, a drag to the right turns
// right, Ctrl-S saves the view, Ctrl-Q quits; the saved camera and the recording say so.
TEST_F(ViewWindow, KeysAndMouseFlySaveAndQuit) {
  if (!have_display()) GTEST_SKIP() << x_server().why();
  if (std::system("command -v xdotool >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "xdotool is not installed (scripts/install-deps.sh installs it)";
  using penumbra::testing::quote;
  const std::string script =
      "export DISPLAY=" + x_server().display() + "\n" + quote(PENUMBRA_CLI) + " view " +
      quote(scene_) + " --size 128x96 --record " + quote(tmp_.file("rec.json")) + " --save " +
      quote(tmp_.file("saved.json")) + " >" + quote(tmp_.file("view.out")) + " 2>&1 &\n" +
      "pid=$!\n"
      "wid=$(timeout 30 xdotool search --sync --onlyvisible --name 'Penumbra viewer' | head -1)\n"
      "[ -n \"$wid\" ] || { kill $pid; exit 90; }\n"
      "sleep 1\n"
      "xdotool mousemove --window $wid 64 48; sleep 0.3\n"
      "xdotool keydown w; sleep 0.6; xdotool keyup w; sleep 0.3\n"
      "xdotool mousedown 1; sleep 0.2\n"
      "for x in 74 84 94 104 114; do xdotool mousemove --window $wid $x 48; sleep 0.1; done\n"
      "xdotool mouseup 1; sleep 0.5\n"
      "xdotool key --delay 0 ctrl+s; sleep 0.5\n"
      "xdotool key --delay 0 ctrl+q\n"
      "for i in $(seq 100); do kill -0 $pid 2>/dev/null || break; sleep 0.1; done\n"
      "kill -0 $pid 2>/dev/null && { kill $pid; exit 91; }\n"
      "wait $pid\n";
  const std::string file = tmp_.write("drive.sh", script);
  const int raw = std::system(("bash " + quote(file)).c_str());
  const int status = raw != -1 && WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  const std::string out = penumbra::testing::slurp(tmp_.file("view.out"));
  ASSERT_EQ(status, 0) << "viewer: " << out;
  // Saved twice: Ctrl-S, then --save at exit, each with its render command.
  EXPECT_NE(out.find("saved " + tmp_.file("saved.json")), std::string::npos) << out;
  EXPECT_NE(out.find("penumbra render " + tmp_.file("saved.json") + " --method ssrc"),
            std::string::npos)
      << out;
  penumbra::Expected<penumbra::spaceland::Scene> saved =
      penumbra::spaceland::load_scene(tmp_.file("saved.json"));
  ASSERT_TRUE(saved.ok()) << saved.error().message;
  const penumbra::spaceland::Camera& c = saved->camera;
  // The scene camera is at z 3.5 looking down -z: forward is towards smaller z, and a turn to
  // the right looks towards +x.
  EXPECT_LT(c.position.z, 3.5f - 0.2f) << c.position.z;
  EXPECT_GT(c.look_at.x - c.position.x, 0.05f);
  EXPECT_EQ(c.width, 128);
  EXPECT_EQ(c.height, 96);
  const std::string recorded = penumbra::testing::slurp(tmp_.file("rec.json"));
  EXPECT_NE(recorded.find("\"camera\""), std::string::npos) << recorded;
}

}  // namespace
