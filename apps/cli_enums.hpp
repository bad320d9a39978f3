// Options whose values are the library's enums (of either world: to_string is found by
// argument-dependent lookup), named on the command line as to_string() names them, so that the
// parser, the help and the reports agree; ranges of real numbers printed as a person writes them.
#pragma once

#include <CLI/CLI.hpp>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "io/json_reader.hpp"
#include "penumbra/flatland/render.hpp"
#include "penumbra/spaceland/render.hpp"

// `value` must outlive the parse; the help lists the names in the order given.
template <class E>
CLI::Option* add_enum_option(CLI::App* app, const std::string& name, E& value,
                             const std::vector<E>& values, const std::string& help) {
  std::vector<std::string> list;
  std::map<std::string, E> names;
  for (E v : values) {
    list.push_back(to_string(v));
    names[list.back()] = v;
  }
  return app
      ->add_option_function<std::string>(
          name, [&value, names](const std::string& s) { value = names.at(s); }, help)
      ->check(CLI::IsMember(list))
      ->default_str(to_string(value));
}

// CLI::Range for real numbers, which prints its bounds as "1000000000.000000": this one says
// "Value 3e38 not in range 0.001 to 1e+09" (shortest round-trip spelling).
inline CLI::Validator real_range(double lo, double hi) {
  const std::string bounds =
      penumbra::io::format_number(lo) + " to " + penumbra::io::format_number(hi);
  return CLI::Validator(
      [lo, hi, bounds](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || std::isnan(v))
          return "Value " + text + " is not a number";
        if (v < lo || v > hi) return "Value " + text + " not in range " + bounds;
        return {};
      },
      "NUMBER in [" + bounds + "]");
}

// A real number above `lo` (or at least `lo`), said plainly: CLI::PositiveNumber's message
// spells out DBL_MAX as its upper bound.
inline CLI::Validator real_above(double lo, bool or_equal) {
  const std::string bound = std::string(or_equal ? ">= " : "> ") + penumbra::io::format_number(lo);
  return CLI::Validator(
      [lo, or_equal, bound](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || std::isnan(v))
          return "Value " + text + " is not a number";
        if (!std::isfinite(v) || v < lo || (!or_equal && v == lo))
          return "Value " + text + " is not a finite number " + bound;
        return {};
      },
      "NUMBER " + bound);
}

// An unsigned 64-bit integer as written: CLI11 alone takes "-1" and 2^64 as 2^64 - 1.
inline CLI::Validator uint64_text() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::uint64_t v = 0;
        const char* end = text.data() + text.size();
        auto [p, ec] = std::from_chars(text.data(), end, v);
        if (text.empty() || ec != std::errc() || p != end)
          return "expected an integer in 0.." + std::to_string(UINT64_MAX) + ", found '" + text +
                 "'";
        return {};
      },
      "UINT64");
}

// A positional file path: an empty one would mean "no file" (the built-in scene) by accident.
inline CLI::Validator non_empty_path() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        return text.empty() ? "expected a file path, found an empty string" : "";
      },
      "");
}

// --exposure of render, paint and compare: a finite number of EV; left empty when not given,
// which means automatic exposure.
inline CLI::Option* add_exposure_option(CLI::App* app, std::optional<float>& ev,
                                        const std::string& help) {
  return app->add_option("--exposure", ev, help)
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            // Stored as a float: a finite double past FLT_MAX would become inf there.
            double v = 0;
            if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v) ||
                std::abs(v) > double(std::numeric_limits<float>::max()))
              return "expected a finite number of EV, found '" + text + "'";
            return {};
          },
          ""));
}
