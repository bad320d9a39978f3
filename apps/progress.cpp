#include "progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <string>

#include "io/image_io.hpp"

std::atomic<bool> g_cancel{false};

namespace {

extern "C" void on_interrupt(int) {
  g_cancel.store(true);
  static const char msg[] = "\npenumbra: stopping after this pass (Ctrl-C again to abort)\n";
  [[maybe_unused]] ssize_t n = write(STDERR_FILENO, msg, sizeof msg - 1);
  // The second one aborts, removing any output still being written.
  std::signal(SIGINT, penumbra::io::remove_staged_and_die);
}

}  // namespace

void watch_interrupts(bool on) {
  std::signal(SIGINT, on ? on_interrupt : SIG_DFL);
}

void draw_progress(const penumbra::RenderProgress& p) {
  const int width = 30;
  const int filled = int(std::lround(std::clamp(p.fraction, 0.0, 1.0) * width));
  const double eta = p.fraction > 0 ? p.elapsed_s * (1 - p.fraction) / p.fraction : 0;
  std::string bar(std::size_t(filled), '#');
  bar.resize(std::size_t(width), '.');
  if (p.target > 0)
    std::fprintf(stderr, "\r[%s] %3.0f%%  %llu/%llu spp  %.1f s, %.1f s left ", bar.c_str(),
                 100 * p.fraction, (unsigned long long)p.samples, (unsigned long long)p.target,
                 p.elapsed_s, eta);
  else
    std::fprintf(stderr, "\r[%s] %3.0f%%  %llu spp  %.1f s, %.1f s left ", bar.c_str(),
                 100 * p.fraction, (unsigned long long)p.samples, p.elapsed_s, eta);
  std::fflush(stderr);
}
