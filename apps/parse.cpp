#include "parse.hpp"

#include <charconv>
#include <cmath>
#include <string>

bool parse_bytes(const std::string& text, std::uint64_t& bytes) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (...) {
    return false;
  }
  std::string unit = text.substr(used);
  double scale = 1;
  if (unit == "" || unit == "B")
    scale = 1;
  else if (unit == "K" || unit == "KiB")
    scale = 1024.0;
  else if (unit == "M" || unit == "MiB")
    scale = 1024.0 * 1024;
  else if (unit == "G" || unit == "GiB")
    scale = 1024.0 * 1024 * 1024;
  else
    return false;
  // Less than a byte ("0.5") would become 0, which means no memory at all.
  if (!(v * scale >= 1) || !std::isfinite(v) || v * scale >= 18446744073709551615.0) return false;
  bytes = std::uint64_t(v * scale);
  return true;
}

bool parse_grid_size(const std::string& text, int& w, int& h) {
  const char* end = text.data() + text.size();
  auto [p, ec] = std::from_chars(text.data(), end, w);
  if (ec != std::errc() || p == end || *p != 'x') return false;
  auto [q, ec2] = std::from_chars(p + 1, end, h);
  return ec2 == std::errc() && q == end && w > 0 && h > 0 && text[0] != '-' && p[1] != '-';
}
