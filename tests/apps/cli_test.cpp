// The command line, run as a user runs it: exit codes, messages, outputs and the JSON report.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "penumbra/flatland/io.hpp"
#include "penumbra/flatland/scene.hpp"
#include "penumbra/io.hpp"
#include "penumbra/version.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;

// 48x32 cells: a lit disk and a wall, small enough that every render takes milliseconds.
constexpr const char* kScene = R"({
  "penumbra": 1,
  "width": 48,
  "height": 32,
  "environment": [0.01, 0.01, 0.02],
  "shapes": [
    { "type": "circle", "center": [12, 16], "radius": 3, "emission": [4, 3, 2] },
    { "type": "box", "center": [30, 16], "size": [2, 20] }
  ]
})";

using Result = penumbra::testing::CliResult;
using penumbra::testing::quote;
using penumbra::testing::slurp;

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(dir_ / "out");
    scene_ = write("scene.json", kScene);
  }

  std::string write(const std::string& name, const std::string& text) const {
    return tmp_.write(name, text);
  }
  // Where outputs go: a directory that must stay empty whenever the CLI fails.
  std::string out(const std::string& name) const { return (dir_ / "out" / name).string(); }

  // Runs the CLI with `args` (each quoted), capturing stdout, stderr and the exit code.
  Result run(const std::vector<std::string>& args) const {
    return penumbra::testing::run_cli(args, dir_);
  }

  // Renders the test scene to out/ with `extra` options; anything but success fails the test.
  Result render_ok(const std::vector<std::string>& extra) const {
    std::vector<std::string> args = {"render", scene_};
    args.insert(args.end(), extra.begin(), extra.end());
    Result r = run(args);
    EXPECT_EQ(r.status, 0) << r.err;
    return r;
  }

  std::vector<std::string> out_files() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_ / "out"))
      names.push_back(e.path().filename().string());
    return names;
  }

  // A failure: the expected exit code, something said on stderr, and nothing (not even a
  // temporary file) left in the output directory.
  void expect_failure(const Result& r, int status) const {
    EXPECT_EQ(r.status, status) << "stdout: " << r.out << "\nstderr: " << r.err;
    EXPECT_FALSE(r.err.empty());
    EXPECT_TRUE(out_files().empty()) << "left behind: " << ::testing::PrintToString(out_files());
  }

  penumbra::testing::TestDir tmp_{"cli"};
  const fs::path& dir_ = tmp_.root();
  std::string scene_;
};

// ---- success -------------------------------------------------------------------------------

TEST_F(Cli, RendersEveryOutputTypeAtOnce) {
  const Result r = render_ok({"-o", out("a.png"), "-o", out("a.exr"), "-o", out("a.pfm")});
  for (const char* name : {"a.png", "a.exr", "a.pfm"}) {
    EXPECT_TRUE(fs::is_regular_file(out(name))) << name;
    EXPECT_GT(fs::file_size(out(name)), 0u) << name;
  }
  EXPECT_EQ(out_files().size(), 3u);  // no temporary files beside them
  EXPECT_NE(r.out.find("a.pfm"), std::string::npos) << r.out;
}

TEST_F(Cli, PfmHasHeaderAndSize) {
  render_ok({"-q", "-o", out("f.pfm")});
  const std::string data = slurp(out("f.pfm"));
  const std::string header = "PF\n48 32\n-1.0\n";  // RGB, 48x32, little-endian
  ASSERT_GE(data.size(), header.size());
  EXPECT_EQ(data.substr(0, header.size()), header);
  EXPECT_EQ(data.size(), header.size() + 48u * 32u * 3u * sizeof(float));
}

TEST_F(Cli, QuietPrintsNothing) {
  const Result r = render_ok({"-q", "-o", out("q.png")});
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_TRUE(fs::exists(out("q.png")));
}

TEST_F(Cli, JsonReportsTimingsMemoryAndParameters) {
  const Result r = render_ok(
      {"--json", "--probe-spacing", "2", "--fix", "none", "--branching", "2", "-o", out("j.pfm")});
  nlohmann::json j;
  ASSERT_NO_THROW(j = nlohmann::json::parse(r.out)) << r.out;  // the whole of stdout
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j.at("method"), "rc");
  EXPECT_EQ(j.at("width"), 48);
  EXPECT_EQ(j.at("height"), 32);
  EXPECT_GT(j.at("time_ms").get<double>(), 0.0);
  ASSERT_TRUE(j.at("stages").is_object());
  EXPECT_FALSE(j.at("stages").empty());
  for (const auto& [name, ms] : j.at("stages").items()) {
    EXPECT_TRUE(ms.is_number()) << name;
    EXPECT_GE(ms.get<double>(), 0.0) << name;
  }
  EXPECT_GT(j.at("memory_bytes").get<std::uint64_t>(), 0u);
  const nlohmann::json& p = j.at("parameters");
  EXPECT_EQ(p.at("probe_spacing"), 2);
  EXPECT_EQ(p.at("fix"), "none");
  EXPECT_EQ(p.at("branching"), 2);
  EXPECT_GT(p.at("cascades").get<int>(), 0);  // derived: 0 on the command line means automatic
  EXPECT_TRUE(fs::exists(out("j.pfm")));
}

// PNGs are exposed automatically unless --exposure says otherwise; the report says which, and
// the exposure is the library's meter reading of the fluence written. Walls in the dark show
// their colour by default (--no-show-walls: as black as the fluence says).
TEST_F(Cli, PngExposureIsAutomaticUnlessGivenAndReported) {
  const Result a = render_ok({"--json", "-o", out("a.png"), "-o", out("a.pfm")});
  const nlohmann::json ja = nlohmann::json::parse(a.out);
  EXPECT_EQ(ja.at("exposure_auto"), true);
  EXPECT_EQ(ja.at("show_walls"), true);
  const penumbra::Expected<penumbra::ImageRgb> f = penumbra::read_rgb_image(out("a.pfm"));
  ASSERT_TRUE(f.ok());
  const penumbra::Expected<penumbra::flatland::SceneDesc> d =
      penumbra::flatland::load_scene(scene_);
  ASSERT_TRUE(d.ok());
  const penumbra::Expected<penumbra::flatland::Scene> sc = penumbra::flatland::build_scene(*d);
  ASSERT_TRUE(sc.ok());
  EXPECT_FLOAT_EQ(ja.at("exposure").get<float>(), penumbra::flatland::auto_exposure(*f, &*sc));
  EXPECT_NE(ja.at("exposure").get<float>(), 0.0f);
  const Result b =
      render_ok({"--json", "--exposure", "1.5", "--no-show-walls", "-o", out("b.png")});
  const nlohmann::json jb = nlohmann::json::parse(b.out);
  EXPECT_EQ(jb.at("exposure_auto"), false);
  EXPECT_EQ(jb.at("exposure").get<float>(), 1.5f);
  EXPECT_EQ(jb.at("show_walls"), false);
  // The text report says it too.
  const Result c = render_ok({"-o", out("c.png")});
  EXPECT_NE(c.out.find("PNG exposure"), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("automatic"), std::string::npos) << c.out;
}

TEST_F(Cli, ThreadCountDoesNotChangeTheResult) {
  render_ok({"-q", "--threads", "1", "-o", out("t1.pfm")});
  render_ok({"-q", "--threads", "2", "-o", out("t2.pfm")});
  const std::string a = slurp(out("t1.pfm")), b = slurp(out("t2.pfm"));
  ASSERT_FALSE(a.empty());
  EXPECT_TRUE(a == b) << "--threads 1 and --threads 2 give different PFM files";
}

TEST_F(Cli, PathTracerReportsSamplesAndParameters) {
  const Result r = render_ok({"--json", "--method", "pt", "--spp", "6", "--nee", "--sampler",
                              "random", "--seed", "9", "-o", out("pt.pfm")});
  nlohmann::json j;
  ASSERT_NO_THROW(j = nlohmann::json::parse(r.out)) << r.out;
  EXPECT_EQ(j.at("method"), "pt");
  EXPECT_EQ(j.at("samples"), 6);
  EXPECT_EQ(j.at("cancelled"), false);
  EXPECT_GE(j.at("intervals").get<std::uint64_t>(), 6u * 48 * 32);  // one ray per sample or more
  const nlohmann::json& p = j.at("parameters");
  EXPECT_EQ(p.at("spp"), 6);
  EXPECT_EQ(p.at("nee"), true);
  EXPECT_EQ(p.at("sampler"), "random");
  EXPECT_EQ(p.at("seed"), 9);
  EXPECT_TRUE(r.err.empty()) << r.err;  // no progress bar when stderr is not a terminal
}

TEST_F(Cli, HolographicCascadesReportStagesAndParameters) {
  const Result r = render_ok({"--json", "--method", "hrc", "--storage", "f16", "--no-cross-blur",
                              "--no-near-segment", "-o", out("h.pfm")});
  nlohmann::json j;
  ASSERT_NO_THROW(j = nlohmann::json::parse(r.out)) << r.out;
  EXPECT_EQ(j.at("method"), "hrc");
  for (const char* stage : {"trace T0-T2", "merge up T3-TN", "merge down R", "views", "gather"})
    EXPECT_TRUE(j.at("stages").contains(stage)) << stage;
  EXPECT_FALSE(j.at("stages").contains("cross blur"));
  EXPECT_GT(j.at("intervals").get<std::uint64_t>(), 4u * 48 * 32);  // T_0 alone: 2 per cell
  const nlohmann::json& p = j.at("parameters");
  EXPECT_EQ(p.at("storage"), "f16");
  EXPECT_EQ(p.at("cross_blur"), false);
  EXPECT_EQ(p.at("near_segment"), false);
  EXPECT_FALSE(p.contains("distance_field"));  // HRC builds no acceleration for long rays
  EXPECT_TRUE(fs::exists(out("h.pfm")));
  fs::remove(out("h.pfm"));
  expect_failure(run({"render", scene_, "--method", "hrc", "--storage", "f8", "-o", out("x.pfm")}),
                 2);
  // Issue 20's options: the defaults, then each spelled out, in the report; the whole-fluence
  // blur is a stage of its own; a corner rule that does not exist is a usage error.
  const Result d = render_ok({"--json", "--method", "hrc", "-o", out("d.pfm")});
  const nlohmann::json jd = nlohmann::json::parse(d.out);
  EXPECT_EQ(jd.at("parameters").at("corners"), "half");
  EXPECT_EQ(jd.at("parameters").at("blur_near_segment"), false);
  EXPECT_FALSE(jd.at("stages").contains("cross blur"));
  EXPECT_EQ(jd.at("parameters").at("wall_fan"), 3);
  EXPECT_EQ(jd.at("parameters").at("near_fan"), 2);
  EXPECT_FLOAT_EQ(jd.at("parameters").at("fan_share").get<float>(), 1.0f / 64);
  // The stages count their work: the fan's rays, ceil(cells / 64) cells but at least 512 (this
  // grid is small), each 2 rays per cone of cascade 3 in each quadrant.
  {
    const nlohmann::json& work = jd.at("stage_work");
    const std::uint64_t cells =
        jd.at("width").get<std::uint64_t>() * jd.at("height").get<std::uint64_t>();
    const std::uint64_t fan =
        std::min<std::uint64_t>(cells, std::max<std::uint64_t>((cells + 63) / 64, 512));
    EXPECT_EQ(work.at("fan").get<std::uint64_t>(), fan * 4 * 16);
    EXPECT_EQ(work.at("gather").get<std::uint64_t>(), 4 * cells);
  }
  EXPECT_FLOAT_EQ(jd.at("parameters").at("even_weight").get<float>(), 0.575f);
  EXPECT_TRUE(jd.at("stages").contains("fan"));
  const Result w = render_ok({"--json", "--method", "hrc", "--corners", "walls",
                              "--blur-near-segment", "--wall-fan", "0", "--near-fan", "5",
                              "--fan-share", "0.25", "--even-weight", "0.5", "-o", out("w.pfm")});
  const nlohmann::json jw = nlohmann::json::parse(w.out);
  EXPECT_FLOAT_EQ(jw.at("parameters").at("even_weight").get<float>(), 0.5f);
  EXPECT_EQ(jw.at("parameters").at("corners"), "walls");
  EXPECT_EQ(jw.at("parameters").at("wall_fan"), 0);
  EXPECT_EQ(jw.at("parameters").at("near_fan"), 5);
  EXPECT_FLOAT_EQ(jw.at("parameters").at("fan_share").get<float>(), 0.25f);
  EXPECT_FALSE(jw.at("stage_work").contains("fan"));
  EXPECT_FALSE(jw.at("stages").contains("fan"));
  EXPECT_EQ(jw.at("parameters").at("blur_near_segment"), true);
  EXPECT_TRUE(jw.at("stages").contains("cross blur"));
  fs::remove(out("d.pfm"));
  fs::remove(out("w.pfm"));
  expect_failure(
      run({"render", scene_, "--method", "hrc", "--corners", "both", "-o", out("x.pfm")}), 2);
  expect_failure(run({"render", scene_, "--method", "hrc", "--wall-fan", "9", "-o", out("x.pfm")}),
                 2);
  expect_failure(run({"render", scene_, "--method", "hrc", "--near-fan", "17", "-o", out("x.pfm")}),
                 2);
  // The even weight's ends are weights (the fan share's check is its own).
  for (const char* w : {"0", "1"})
    render_ok({"--method", "hrc", "--even-weight", w, "-q", "-o", out("e.pfm")});
  fs::remove(out("e.pfm"));
  for (const char* share : {"0", "1.5", "nan"})
    expect_failure(
        run({"render", scene_, "--method", "hrc", "--fan-share", share, "-o", out("x.pfm")}), 2);
  expect_failure(
      run({"render", scene_, "--method", "hrc", "--even-weight", "1.5", "-o", out("x.pfm")}), 2);
}

// Half precision converts with F16C where the CPU has it and through tables otherwise
// (PENUMBRA_NO_F16C=1): both round to nearest even, so the files are the same bytes.
TEST_F(Cli, HalfPrecisionIsTheSameWithAndWithoutF16c) {
  const std::string cli = penumbra::testing::quote(PENUMBRA_CLI);
  for (const char* env : {"PENUMBRA_NO_F16C=1", "PENUMBRA_NO_F16C=0"}) {
    const std::string out_file = out(std::string(env).back() == '1' ? "tables.pfm" : "f16c.pfm");
    const std::string cmd = std::string(env) + " " + cli +
                            " render --method hrc --storage f16 -q -o " +
                            penumbra::testing::quote(out_file);
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  const std::string a = slurp(out("tables.pfm")), b = slurp(out("f16c.pfm"));
  ASSERT_FALSE(a.empty());
  EXPECT_TRUE(a == b) << "f16 storage differs between F16C and the conversion tables";
}

TEST_F(Cli, PathTracerSkippingEmptySpaceDoesNotChangeTheResult) {
  const std::vector<std::string> pt = {"-q", "--method", "pt", "--spp", "4", "--bounces", "2"};
  std::vector<std::vector<std::string>> variants = {
      {}, {"--no-blocks"}, {"--no-distance-field"}, {"--no-blocks", "--no-distance-field"}};
  std::string first;
  for (std::size_t k = 0; k < variants.size(); ++k) {
    std::vector<std::string> args = pt;
    args.insert(args.end(), variants[k].begin(), variants[k].end());
    std::string name = "v";
    name += std::to_string(k);
    name += ".pfm";
    const std::string file = out(name);
    args.insert(args.end(), {"-o", file});
    render_ok(args);
    const std::string data = slurp(file);
    if (k == 0) first = data;
    EXPECT_TRUE(!data.empty() && data == first) << ::testing::PrintToString(variants[k]);
  }
}

TEST_F(Cli, PathTracerTimeLimitStops) {
  const Result r = render_ok({"--json", "--method", "pt", "--time", "0.5", "-o", out("t.pfm")});
  nlohmann::json j;
  ASSERT_NO_THROW(j = nlohmann::json::parse(r.out)) << r.out;
  EXPECT_GE(j.at("samples").get<int>(), 1);
  EXPECT_EQ(j.at("parameters").at("spp"), 0);  // --time alone: no sample limit
}

// Ctrl-C: the render stops after its current pass, writes the image of the samples so far, says
// how many, and exits 130.
TEST_F(Cli, InterruptWritesWhatItHas) {
  std::string cmd = quote(PENUMBRA_CLI);
  for (const std::string& piece :
       {std::string(" render "), quote(scene_), std::string(" --method pt --spp 100000000 -q -o "),
        quote(out("i.pfm")), std::string(" 2>"), quote((dir_ / "int_err.txt").string()),
        " & pid=$!; " + penumbra::testing::interrupt_once_caught() + "; wait $pid; exit $?"})
    cmd += piece;
  std::string shell = "bash -c ";
  shell += quote(cmd);
  const int raw = std::system(shell.c_str());
  ASSERT_TRUE(WIFEXITED(raw));
  EXPECT_EQ(WEXITSTATUS(raw), 130);
  EXPECT_TRUE(fs::is_regular_file(out("i.pfm")));
  EXPECT_EQ(out_files().size(), 1u);
  const std::string err = slurp(dir_ / "int_err.txt");
  EXPECT_NE(err.find("interrupted; wrote the image of"), std::string::npos) << err;
}

TEST_F(Cli, PathTracerBadOptionsAreUsageErrors) {
  expect_failure(run({"render", scene_, "--method", "pt", "--spp", "0", "-o", out("x.pfm")}), 2);
  expect_failure(run({"render", scene_, "--method", "pt", "--spp", "-3", "-o", out("x.pfm")}), 2);
  expect_failure(run({"render", scene_, "--method", "pt", "--time", "-1", "-o", out("x.pfm")}), 2);
  expect_failure(
      run({"render", scene_, "--method", "pt", "--sampler", "sobol", "-o", out("x.pfm")}), 2);
  expect_failure(run({"render", scene_, "--method", "mc", "-o", out("x.pfm")}), 2);
}

TEST_F(Cli, HelpMentionsTheOptions) {
  const Result top = run({"--help"});
  EXPECT_EQ(top.status, 0) << top.err;
  EXPECT_NE(top.out.find("render"), std::string::npos) << top.out;
  EXPECT_NE(top.out.find("--version"), std::string::npos) << top.out;

  const Result r = run({"render", "--help"});
  EXPECT_EQ(r.status, 0) << r.err;
  for (const char* opt : {"--output", "--probe-spacing", "--branching", "--fix", "--threads",
                          "--max-memory", "--json", "--extend", "--storage", "--no-cross-blur",
                          "--no-near-segment", "--corners", "--blur-near-segment"})
    EXPECT_NE(r.out.find(opt), std::string::npos) << opt << " missing from:\n" << r.out;
}

TEST_F(Cli, VersionPrintsTheLibraryVersion) {
  const Result r = run({"--version"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find(penumbra::kVersion), std::string::npos) << r.out;
}

// ---- usage errors: exit 2 ------------------------------------------------------------------

TEST_F(Cli, UnknownOptionIsAUsageError) {
  expect_failure(run({"render", scene_, "-o", out("x.png"), "--bogus"}), 2);
}

// An option another 2D method reads was silently ignored (`--method hrc --fix none`); it is
// refused, naming the methods that read it, and nothing is written.
TEST_F(Cli, OptionsOfAnotherMethodAreRefused) {
  struct Case {
    std::vector<std::string> args;
    const char* message;
  };
  for (const Case& c : {
           Case{{"--method", "hrc", "--fix", "none"}, "--fix applies to --method rc only, not hrc"},
           Case{{"--method", "hrc", "--extend"}, "--extend applies to --method rc only, not hrc"},
           Case{{"--spp", "10"}, "--spp applies to --method pt only, not rc (the default)"},
           Case{{"--method", "pt", "--interval", "2"}, "--interval applies to --method rc only"},
           Case{{"--method", "rc", "--near-fan", "3"}, "--near-fan applies to --method hrc only"},
           Case{{"--method", "rc", "--even-weight", "0.5"},
                "--even-weight applies to --method hrc"},
           Case{{"--method", "hrc", "--no-distance-field"},
                "--no-distance-field applies to --method rc or pt only, not hrc"},
       }) {
    std::vector<std::string> args = {"render", scene_, "-o", out("x.png")};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const Result r = run(args);
    expect_failure(r, 2);
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
  }
  // Each method still takes its own.
  render_ok({"--method", "hrc", "--near-fan", "3", "--even-weight", "0.5", "-o", out("h.png")});
  render_ok({"--method", "pt", "--spp", "2", "--no-blocks", "-o", out("p.png")});
}

// A mistyped subcommand or option is a usage error that names the closest one.
TEST_F(Cli, MistypedNamesGetADidYouMean) {
  Result r = run({"rendr", scene_});
  expect_failure(r, 2);
  EXPECT_NE(r.err.find("Did you mean 'penumbra render'?"), std::string::npos) << r.err;
  r = run({"render", scene_, "-o", out("x.png"), "--bounce", "2"});
  expect_failure(r, 2);
  EXPECT_NE(r.err.find("Did you mean --bounces (for --bounce)?"), std::string::npos) << r.err;
  r = run({"compare", scene_, scene_, "--heatmp=x.png"});
  expect_failure(r, 2);
  EXPECT_NE(r.err.find("Did you mean --heatmap"), std::string::npos) << r.err;
  // Nothing close: no guess.
  r = run({"render", scene_, "-o", out("x.png"), "--zzzzzzzz"});
  expect_failure(r, 2);
  EXPECT_EQ(r.err.find("Did you mean"), std::string::npos) << r.err;
}

TEST_F(Cli, MissingOutputIsAUsageError) {
  const Result r = run({"render", scene_});
  expect_failure(r, 2);
  EXPECT_NE(r.err.find("output"), std::string::npos) << r.err;
}

TEST_F(Cli, UnknownOutputExtensionIsAUsageError) {
  const Result r = run({"render", scene_, "-o", out("x.bmp")});
  expect_failure(r, 2);
  EXPECT_NE(r.err.find("x.bmp"), std::string::npos) << r.err;
}

TEST_F(Cli, UnknownExtensionAmongGoodOnesWritesNothing) {
  expect_failure(run({"render", scene_, "-o", out("x.png"), "-o", out("x.bmp")}), 2);
}

// Bounds of real-valued options read as a person writes them, not "1000000.000000".
TEST_F(Cli, RealRangesPrintReadableBounds) {
  const Result r =
      run({"render", scene_, "--extend", "--extend-length", "0.5", "-o", out("x.png")});
  expect_failure(r, 2);
  EXPECT_NE(r.err.find("Value 0.5 not in range 1 to 1e+06"), std::string::npos) << r.err;
}

TEST_F(Cli, BranchingThreeIsAUsageError) {
  const Result r = run({"render", scene_, "--branching", "3", "-o", out("x.png")});
  expect_failure(r, 2);
  EXPECT_NE(r.err.find("branching"), std::string::npos) << r.err;
}

TEST_F(Cli, UnknownFixIsAUsageError) {
  const Result r = run({"render", scene_, "--fix", "sideways", "-o", out("x.png")});
  expect_failure(r, 2);
  EXPECT_NE(r.err.find("sideways"), std::string::npos) << r.err;
}

TEST_F(Cli, UnparsableMemoryLimitIsAUsageError) {
  const Result r = run({"render", scene_, "--max-memory", "banana", "-o", out("x.png")});
  expect_failure(r, 2);
  EXPECT_NE(r.err.find("banana"), std::string::npos) << r.err;
}

TEST_F(Cli, NoSubcommandIsAUsageError) {
  expect_failure(run({}), 2);
}

// ---- input and runtime errors: exit 1 ------------------------------------------------------

TEST_F(Cli, BadSceneNamesFileAndJsonPath) {
  const std::string bad = write("bad_radius.json", R"({
    "penumbra": 1, "width": 48, "height": 32,
    "shapes": [ { "type": "circle", "center": [10, 10], "radius": -1 } ]
  })");
  const Result r = run({"render", bad, "-o", out("x.png")});
  expect_failure(r, 1);
  EXPECT_NE(r.err.find("bad_radius.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("shapes[0].radius"), std::string::npos) << r.err;
}

// Emission 3e38 is finite, so the format allows it, but its fluence is not: every method used to
// write infinities or NaN and exit 0 (the fuzzing report of issue 16).
TEST_F(Cli, SceneTooBrightForFloatsIsRefusedNamingTheValue) {
  const std::string light = write("light.json", R"({
    "penumbra": 1, "width": 64, "height": 64,
    "shapes": [ { "type": "circle", "center": [32, 32], "radius": 4, "emission": [3e38, 0, 0] } ]
  })");
  const std::string sky = write("sky.json", R"({
    "penumbra": 1, "width": 64, "height": 64, "environment": [0, 3e38, 0] })");
  for (const std::string method : {"rc", "hrc", "pt"}) {
    std::vector<std::string> args = {"render", light, "--method", method, "-o", out("x.pfm")};
    if (method == "pt") args.insert(args.end(), {"--spp", "4"});
    Result r = run(args);
    expect_failure(r, 1);
    EXPECT_NE(r.err.find("light.json: shapes[0].emission: 3e+38 is too bright to render"),
              std::string::npos)
        << r.err;
    args[1] = sky;
    r = run(args);
    expect_failure(r, 1);
    EXPECT_NE(r.err.find("sky.json: environment: 3e+38 is too bright"), std::string::npos) << r.err;
  }
}

// Outputs are renamed into place, which only needs the directory's permission: a read-only file
// the user keeps was silently replaced. Refused up front, as cp refuses it; nothing is written.
TEST_F(Cli, WriteProtectedOutputIsNotReplaced) {
  const fs::path kept = dir_ / "kept";
  fs::create_directories(kept);
  const std::string ro = (kept / "ro.pfm").string();
  std::ofstream(ro) << "mine";
  ASSERT_EQ(::chmod(ro.c_str(), 0444), 0);
  const Result r = run({"render", scene_, "-o", out("first.png"), "-o", ro});
  expect_failure(r, 1);
  EXPECT_NE(r.err.find(ro + ": the file is write-protected (mode 0444); not replacing it"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(slurp(ro), "mine");
  // A writable file is replaced as before.
  ASSERT_EQ(::chmod(ro.c_str(), 0644), 0);
  EXPECT_EQ(run({"render", scene_, "-q", "-o", ro}).status, 0);
  EXPECT_NE(slurp(ro), "mine");
}

// SIGINT or SIGTERM while outputs are being written (a large image takes a while) used to leave
// "x.pfm.tmp.<pid>.0" beside the targets. The staged files are removed and the process still
// dies of the signal. The signal is sent as soon as a temporary file shows up.
TEST_F(Cli, SignalWhileWritingLeavesNoTemporaryFile) {
  const std::string big = write("big.json", R"({"penumbra": 1, "width": 2048, "height": 2048,
      "environment": [0.1, 0.1, 0.1]})");
  for (int sig : {SIGTERM, SIGINT}) {
    const fs::path where = dir_ / ("signal" + std::to_string(sig));
    fs::create_directories(where);
    const std::vector<std::string> args = {PENUMBRA_CLI,
                                           "render",
                                           big,
                                           "-q",
                                           "--method",
                                           "rc",
                                           "--probe-spacing",
                                           "4",
                                           "-o",
                                           (where / "a.pfm").string(),
                                           "-o",
                                           (where / "a.exr").string(),
                                           "-o",
                                           (where / "a.png").string()};
    const pid_t pid = penumbra::testing::start_program(args);
    ASSERT_GE(pid, 0);
    const bool seen = penumbra::testing::wait_for_staged_file(pid, where);
    ASSERT_TRUE(seen) << "no temporary file seen while writing; signal " << sig;
    ::kill(pid, sig);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "status " << status;
    EXPECT_FALSE(penumbra::testing::has_staged_file(where)) << "signal " << sig;
  }
}

TEST_F(Cli, MissingSceneFileNamesIt) {
  const Result r = run({"render", (dir_ / "no_such_scene.json").string(), "-o", out("x.png")});
  expect_failure(r, 1);
  EXPECT_NE(r.err.find("no_such_scene.json"), std::string::npos) << r.err;
}

TEST_F(Cli, MalformedJsonNamesFileAndLine) {
  const std::string bad = write("broken.json", "{\n  \"penumbra\": 1,\n  \"width\": 48,,\n}\n");
  const Result r = run({"render", bad, "-o", out("x.png")});
  expect_failure(r, 1);
  EXPECT_NE(r.err.find("broken.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("line 3"), std::string::npos) << r.err;
}

TEST_F(Cli, OutputInMissingDirectoryFails) {
  const fs::path missing = dir_ / "out" / "no_such_dir";
  const Result r = run({"render", scene_, "-o", (missing / "x.pfm").string()});
  expect_failure(r, 1);
  EXPECT_NE(r.err.find("x.pfm"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(missing));
}

// Disabled: the CLI writes outputs one by one, so a.pfm stays when b.pfm then fails. Enable once
// it checks every output's directory before writing (or removes what it wrote on failure).
TEST_F(Cli, FailedSecondOutputLeavesNoFirstOutput) {
  const Result r = run(
      {"render", scene_, "-o", out("a.pfm"), "-o", (dir_ / "out" / "nodir" / "b.pfm").string()});
  expect_failure(r, 1);
}

TEST_F(Cli, MemoryLimitIsEnforcedBeforeRendering) {
  const Result r = run({"render", scene_, "--max-memory", "1K", "-o", out("x.png")});
  expect_failure(r, 1);
  EXPECT_NE(r.err.find("working memory"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("limit"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--max-memory"), std::string::npos) << r.err;
}

// The largest grid the format allows needs about 50 GiB: refused before the grid is allocated.
TEST_F(Cli, LargestGridIsRefusedUpFront) {
  const std::string huge =
      write("huge.json", R"({"penumbra": 1, "width": 16384, "height": 16384})");
  const Result r = run({"render", huge, "-o", out("x.pfm")});
  expect_failure(r, 1);
  EXPECT_NE(r.err.find("huge.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("16384x16384"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("limit"), std::string::npos) << r.err;
  for (const char* method : {"rc", "hrc"}) {  // on the GPU too, where the host holds less
    const Result g =
        run({"render", huge, "--device", "gpu", "--method", method, "-o", out("x.pfm")});
    expect_failure(g, 1);
    EXPECT_NE(g.err.find("16384x16384"), std::string::npos) << g.err;
  }
}

// --device gpu (lavapipe in CI): the JSON names the device and gives the GPU time of each pass,
// the GPU memory and the bytes uploaded.
TEST_F(Cli, GpuRenderReportsDevicePassesAndMemory) {
  for (const char* method : {"rc", "hrc"}) {
    const Result r =
        render_ok({"--json", "--method", method, "--device", "gpu", "-o", out("g.pfm")});
    nlohmann::json j;
    ASSERT_NO_THROW(j = nlohmann::json::parse(r.out)) << r.out;
    EXPECT_NE(j.at("device"), "cpu");
    const nlohmann::json& stages = j.at("stages");
    EXPECT_TRUE(stages.contains(std::string(method) == "rc" ? "gpu cascade 0" : "gpu merge down R"))
        << stages.dump();
    EXPECT_TRUE(stages.contains("gpu upload")) << stages.dump();
    EXPECT_TRUE(stages.contains("setup and transfers")) << stages.dump();
    EXPECT_GT(j.at("gpu_memory_bytes").get<std::uint64_t>(), 0u);
    EXPECT_GT(j.at("uploaded_bytes").get<std::uint64_t>(), 0u);
  }
}

TEST_F(Cli, ExtendNeedsAFixOtherThanBilinear) {
  const Result r = run({"render", scene_, "--extend", "-o", out("x.png")});
  expect_failure(r, 2);  // a combination of options that cannot work: usage error
  EXPECT_NE(r.err.find("extend"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("bilinear"), std::string::npos) << r.err;
}

// The library names options by field (`rc.fix`); the command line shows its flags instead.
TEST_F(Cli, OptionMessagesNameTheFlags) {
  struct Case {
    std::vector<std::string> args;
    std::string flag;
  };
  const Case cases[] = {
      {{"--extend"}, "--fix"},
      {{"--extend", "--fix", "none", "--preaverage"}, "--preaverage"},
      {{"--cascades", "16", "--directions", "64"}, "--directions"},
      {{"--max-memory", "1K"}, "--max-memory"},
      {{"--method", "pt", "--spp", "0"}, "--time"},
      {{"--method", "pt", "--device", "gpu"}, "path tracer"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = {"render", scene_, "-o", out("x.png")};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const Result r = run(args);
    EXPECT_NE(r.status, 0) << c.flag;
    EXPECT_NE(r.err.find(c.flag), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find('`'), std::string::npos) << "a field name left in: " << r.err;
  }
}

// A failed run leaves files that were there before untouched.
TEST_F(Cli, FailedRunKeepsExistingOutputs) {
  const std::string keep = out("keep.pfm");
  {
    std::ofstream f(keep);
    f << "precious";
  }
  fs::create_directories(out("dir.pfm"));
  const Result r = run({"render", scene_, "-o", keep, "-o", out("dir.pfm")});
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_EQ(slurp(keep), "precious");
  for (const auto& e : fs::directory_iterator(dir_ / "out"))
    EXPECT_TRUE(e.path().filename() == "keep.pfm" || e.path().filename() == "dir.pfm") << e.path();
}

TEST_F(Cli, BadOptionValuesAreUsageErrors) {
  for (const std::vector<std::string>& bad : {std::vector<std::string>{"--interval", "nan"},
                                              {"--exposure", "inf"},
                                              {"--exposure", "1e40"},  // finite, not as a float
                                              {"--interval", "0"},
                                              {"--time", "-1"},
                                              {"--max-memory", "1e30G"},
                                              {"--interval", "1e-18"}}) {
    std::vector<std::string> args = {"render", scene_, "-o", out("x.pfm")};
    args.insert(args.end(), bad.begin(), bad.end());
    const Result r = run(args);
    EXPECT_EQ(r.status, 2) << bad[0] << " " << bad[1] << ": " << r.err;
    EXPECT_FALSE(fs::exists(out("x.pfm")));
  }
}

TEST_F(Cli, ExtendWorksWithVanillaMerge) {
  render_ok({"-q", "--extend", "--fix", "none", "-o", out("e.pfm")});
  EXPECT_TRUE(fs::exists(out("e.pfm")));
}

}  // namespace
