// One virtual X server (Xvfb) for a test process, for the tests that open windows (the painter,
// the viewer).
#pragma once

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>

#include "test_support.hpp"

namespace penumbra::testing {

// One Xvfb for the test process. It picks a free display itself (-displayfd), so test processes
// running side by side never share or steal one.
class XServer {
 public:
  XServer() {
    if (std::system("command -v Xvfb >/dev/null 2>&1") != 0) {
      why_ = "Xvfb is not installed (scripts/install-deps.sh installs it)";
      return;
    }
    installed_ = true;
    const std::string tag = std::to_string(getpid());
    const std::filesystem::path dir = std::filesystem::temp_directory_path();
    const std::filesystem::path number = dir / ("penumbra_xvfb_display_" + tag),
                                pidfile = dir / ("penumbra_xvfb_pid_" + tag),
                                log = dir / ("penumbra_xvfb_log_" + tag);
    using penumbra::testing::quote;
    const std::string cmd = "Xvfb -displayfd 3 -screen 0 1280x1024x24 -nolisten tcp 3>" +
                            quote(number.string()) + " 2>" + quote(log.string()) +
                            " >/dev/null & echo $! > " + quote(pidfile.string());
    // Three tries: on a loaded machine (the sanitizer run, tests side by side) a server can be
    // slow to come up or lose a race for a display number; each try waits up to 20 s.
    for (int attempt = 0; attempt < 3 && display_.empty(); ++attempt) {
      if (std::system(cmd.c_str()) != 0) continue;
      pid_ = std::atoi(penumbra::testing::slurp(pidfile).c_str());
      // Xvfb writes the display number and a newline once it accepts connections.
      for (int tries = 0; tries < 400; ++tries) {
        const std::string n = penumbra::testing::slurp(number);
        if (!n.empty() && n.back() == '\n') {
          display_ = ":" + n.substr(0, n.size() - 1);
          break;
        }
        if (pid_ <= 0 || kill(pid_, 0) != 0) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
      if (display_.empty()) {
        std::ostringstream why;
        why << "Xvfb did not start (try " << attempt + 1 << "): " << penumbra::testing::slurp(log)
            << "\n";
        why_ += why.str();
        stop();
      }
    }
    if (!display_.empty()) why_.clear();
    for (const std::filesystem::path& p : {number, pidfile, log}) std::filesystem::remove(p);
  }
  ~XServer() { stop(); }
  bool installed() const { return installed_; }
  const std::string& display() const { return display_; }
  const std::string& why() const { return why_; }

 private:
  void stop() {
    if (pid_ > 0) kill(pid_, SIGTERM);
    pid_ = 0;
  }
  std::string display_, why_;
  bool installed_ = false;
  int pid_ = 0;
};

inline XServer& x_server() {
  static XServer server;
  return server;
}

}  // namespace penumbra::testing
