// Helpers shared by the test files.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "penumbra/flatland/render.hpp"
#include "penumbra/flatland/scene.hpp"

namespace penumbra::testing {

using namespace penumbra::flatland;

// A scene from a description the test expects to be valid (a failure is reported, and an empty
// scene returned).
inline Scene build_valid(const SceneDesc& d) {
  Expected<Scene> s = build_scene(d);
  EXPECT_TRUE(s.ok()) << (s.ok() ? "" : s.error().message);
  return s.ok() ? *s : Scene{};
}

// render() where the test expects it to succeed.
inline RenderResult render_valid(const Scene& s, const RenderOptions& o = {}) {
  Expected<RenderResult> r = render(s, o);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.ok() ? *r : RenderResult{};
}

// The fluence render() gives where the test expects it to succeed.
inline ImageRgb fluence_of(const Scene& s, const RenderOptions& o) {
  return render_valid(s, o).fluence;
}

// The path tracer with `spp` samples per cell.
inline RenderOptions pt_options(int spp, Sampler sampler = Sampler::r1, bool nee = false) {
  RenderOptions o;
  o.method = Method::pt;
  o.pt.spp = spp;
  o.pt.sampler = sampler;
  o.pt.nee = nee;
  return o;
}

// A document a loader must refuse, for value-parameterised error tests: the JSON path its
// message names right after "scene.json: ", and another piece the message must contain.
struct ErrorCase {
  const char* name;
  std::string json;
  std::string path;
  std::string words;
};

// gtest prints a parameter it cannot print as the bytes of the object (heap addresses that
// change from run to run); a case is its name.
inline void PrintTo(const ErrorCase& c, std::ostream* os) {
  *os << c.name;
}

// Checks what a loader said about `c`, parsed as "scene.json".
inline void expect_refused(bool ok, const std::string& message, const ErrorCase& c) {
  ASSERT_FALSE(ok) << c.json;
  EXPECT_EQ(message.rfind("scene.json: " + c.path + ": ", 0), 0u) << message;
  EXPECT_NE(message.find(c.words), std::string::npos) << message;
}

// A directory of the running test's own under the test temporary directory, removed at the end.
class TestDir {
 public:
  explicit TestDir(const std::string& prefix) {
    static std::atomic<unsigned> counter{0};
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    root_ = std::filesystem::path(::testing::TempDir()) /
            ("penumbra_" + prefix + "_" + info->test_suite_name() + "_" + info->name() + "_" +
             std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(root_);
    std::filesystem::create_directories(root_);
  }
  ~TestDir() {
    std::error_code ec;
    std::filesystem::remove_all(root_, ec);
  }
  TestDir(const TestDir&) = delete;
  TestDir& operator=(const TestDir&) = delete;

  const std::filesystem::path& root() const { return root_; }
  std::string file(const std::string& name) const { return (root_ / name).string(); }
  // Writes `text` to the file `name` and returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(file(name), std::ios::binary) << text;
    return file(name);
  }
  // Names of the entries in `sub` (the root by default), to catch stray files.
  std::vector<std::string> entries(const std::string& sub = "") const {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(root_ / sub))
      names.push_back(e.path().filename().string());
    return names;
  }

 private:
  std::filesystem::path root_;
};

// The whole content of a file ("" when it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Single-quoted for /bin/sh, so temporary paths with odd characters stay one word.
inline std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// A shell snippet for a script that started a program in the background ($pid): waits until it
// catches SIGINT (its handler set: the SigCgt mask of Linux's /proc/PID/status), at most 60 s,
// then sends it one. A non-interactive shell starts background jobs with SIGINT ignored, so a
// signal sent before the handler is set is lost and the job runs on: a fixed `sleep 1` lost that
// race on a loaded machine under the sanitizers, and the render of 10^8 samples never ended.
inline std::string interrupt_once_caught() {
  return "for i in $(seq 6000); do m=$(sed -n 's/^SigCgt:[[:space:]]*//p' /proc/$pid/status "
         "2>/dev/null); [ -n \"$m\" ] && (( 0x$m & 2 )) && break; sleep 0.01; done; "
         "kill -INT $pid";
}

struct CliResult {
  int status = -1;  // the exit code, or -1 when the process did not exit normally
  std::string out, err;
};

// Runs `program` with `args`, each quoted, capturing stdout and stderr in files under `dir` and
// the exit code (124 when it ran for more than 5 minutes); with `in_dir`, from inside `dir`.
inline CliResult run_program(const std::string& program, const std::vector<std::string>& args,
                             const std::filesystem::path& dir, bool in_dir = false) {
  std::string cmd;
  if (in_dir) {
    cmd += "cd ";
    cmd += quote(dir.string());
    cmd += " && ";
  }
  // A hang fails the test after 5 minutes (status 124) instead of holding ctest for its limit.
  cmd += "timeout -k 10 300 ";
  cmd += quote(program);
  // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "literal" + std::string&&.
  for (const std::string& a : args) {
    cmd += ' ';
    cmd += quote(a);
  }
  const std::filesystem::path o = dir / "stdout.txt", e = dir / "stderr.txt";
  cmd += " >";
  cmd += quote(o.string());
  cmd += " 2>";
  cmd += quote(e.string());
  cmd += " </dev/null";
  const int raw = std::system(cmd.c_str());
  CliResult r;
  r.status = raw != -1 && WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = slurp(o);
  r.err = slurp(e);
  return r;
}

// Starts `argv` (the program first) in a child process without waiting for it, its output
// thrown away when `quiet`; returns its pid (or -1).
inline pid_t start_program(const std::vector<std::string>& argv, bool quiet = false) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (quiet) {
      const int null = ::open("/dev/null", O_WRONLY);
      ::dup2(null, STDOUT_FILENO);
      ::dup2(null, STDERR_FILENO);
    }
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  return pid;
}

// Whether `dir` holds a temporary output file (NAME.tmp.PID.N, docs/RELIABILITY.md).
inline bool has_staged_file(const std::filesystem::path& dir) {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    if (e.path().filename().string().find(".tmp.") != std::string::npos) return true;
  return false;
}

// Waits, up to 2 minutes, until `dir` holds a temporary output file while child `pid` runs;
// false when the child ended first (it is then reaped) or none appeared.
inline bool wait_for_staged_file(pid_t pid, const std::filesystem::path& dir) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (std::chrono::steady_clock::now() < give_up) {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) return false;
    if (has_staged_file(dir)) return true;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return false;
}

// The command line (PENUMBRA_CLI), as run_program.
inline CliResult run_cli(const std::vector<std::string>& args, const std::filesystem::path& dir) {
  return run_program(PENUMBRA_CLI, args, dir);
}

}  // namespace penumbra::testing
