// The JSON reader shared by the scene loader and the stroke files.
#include "io/json_reader.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string_view>
#include <utility>
#include <vector>

namespace penumbra::io {

using nlohmann::json;

namespace {

// Line and column (1-based) of a byte offset, for JSON syntax errors.
std::pair<std::size_t, std::size_t> line_column(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  std::size_t line = 1, line_start = 0;
  for (std::size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  }
  return {line, offset - line_start + 1};
}

// A SAX pass that only tracks the JSON path, to name the value nlohmann refuses as out of
// range (it rejects 1e999 while parsing, before any value reaches the walk).
class PathTracker {
 public:
  bool null() { return value(); }
  bool boolean(bool) { return value(); }
  bool number_integer(json::number_integer_t) { return value(); }
  bool number_unsigned(json::number_unsigned_t) { return value(); }
  bool number_float(json::number_float_t, const std::string&) { return value(); }
  bool string(std::string&) { return value(); }
  bool binary(json::binary_t&) { return value(); }
  bool start_object(std::size_t) { return push(false); }
  bool key(std::string& k) {
    stack_.back().key = k;
    return true;
  }
  bool end_object() { return pop(); }
  bool start_array(std::size_t) { return push(true); }
  bool end_array() { return pop(); }
  bool parse_error(std::size_t, const std::string& token, const nlohmann::detail::exception&) {
    error_path_ = path();
    token_ = token;
    return false;
  }

  const std::string& error_path() const { return error_path_; }
  const std::string& token() const { return token_; }

 private:
  struct Frame {
    bool array;
    std::size_t index = 0;
    std::string key;
  };
  bool value() {
    if (!stack_.empty() && stack_.back().array) ++stack_.back().index;
    return true;
  }
  bool push(bool array) {
    stack_.push_back({array, 0, {}});
    return true;
  }
  bool pop() {
    stack_.pop_back();
    return value();
  }
  std::string path() const {
    std::string p;
    for (const Frame& f : stack_) {
      // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "[" + ... + "]" here.
      if (f.array) {
        p += '[';
        p += std::to_string(f.index);
        p += ']';
      } else {
        if (!p.empty()) p += '.';
        p += f.key;
      }
    }
    return p.empty() ? "(document)" : p;
  }

  std::vector<Frame> stack_;
  std::string error_path_, token_;
};

}  // namespace

nlohmann::json parse_json(std::string_view text, const std::string& file) {
  try {
    return json::parse(text.begin(), text.end());
  } catch (const json::out_of_range&) {
    // nlohmann refuses numbers beyond double range (1e999) while parsing: find their path.
    PathTracker tracker;
    json::sax_parse(text.begin(), text.end(), &tracker);
    throw JsonFailure{file + ": " + tracker.error_path() + ": expected a finite number, found " +
                      (tracker.token().empty() ? "a number out of range" : tracker.token()) +
                      " (out of range)"};
  } catch (const json::parse_error& e) {
    // nlohmann's byte is the 1-based index of the last character read (the offending one).
    auto [line, column] = line_column(text, e.byte > 0 ? e.byte - 1 : 0);
    std::string detail = e.what();
    // Drop nlohmann's "[json.exception...] parse error at line L, column C: " prefix.
    if (auto colon = detail.find(": "); colon != std::string::npos)
      detail = detail.substr(colon + 2);
    throw JsonFailure{file + ": line " + std::to_string(line) + ", column " +
                      std::to_string(column) + ": invalid JSON: " + detail};
  }
}

void fail(const std::string& file, const std::string& path, const std::string& what) {
  throw JsonFailure{file + ": " + path + ": " + what};
}

std::string format_number(float v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string format_number(double v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string format_mib(std::uint64_t bytes) {
  return format_rounded(double(bytes) / double(1 << 20)) + " MiB";
}

std::string format_rounded(double v) {
  char buf[40];
  const double a = std::fabs(v);
  if (a >= 1e3 && a < 1e7) {  // "41700", not "4.17e+04"
    const double unit = std::pow(10.0, std::floor(std::log10(a)) - 2);
    std::snprintf(buf, sizeof buf, "%.0f", std::round(v / unit) * unit);
  } else {
    std::snprintf(buf, sizeof buf, "%.3g", v);
  }
  return buf;
}

std::string describe(const json& j) {
  switch (j.type()) {
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
      return j.dump();
    case json::value_t::number_float: {
      // "512.0", not "512": the point is that it is not an integer.
      double d = j.get<double>();
      std::string s = format_number(d);
      if (std::isfinite(d) && d == std::floor(d) && std::fabs(d) < 1e15) s += ".0";
      return s;
    }
    case json::value_t::string: {
      std::string s = j.dump();
      if (s.size() > 60) s = s.substr(0, 56) + "...\"";
      return "the string " + s;
    }
    case json::value_t::boolean:
      return j.get<bool>() ? "true" : "false";
    case json::value_t::null:
      return "null";
    case json::value_t::array:
      return "an array of " + std::to_string(j.size()) + (j.size() == 1 ? " element" : " elements");
    case json::value_t::object:
      return "an object";
    default:
      return "an unsupported value";
  }
}

const char* expected_text(Range r) {
  switch (r) {
    case Range::any:
      return "a finite number";
    case Range::nonneg:
      return "a number >= 0";
    case Range::positive:
      return "a number > 0";
    case Range::unit:
      return "a number in [0, 1]";
  }
  return "a number";
}

bool in_range(double v, Range r) {
  if (!std::isfinite(v)) return false;
  switch (r) {
    case Range::any:
      return true;
    case Range::nonneg:
      return v >= 0;
    case Range::positive:
      return v > 0;
    case Range::unit:
      return v >= 0 && v <= 1;
  }
  return false;
}

void JsonReader::fail_at(const std::string& path, const std::string& what) const {
  fail(file_, path, what);
}
void JsonReader::expected(const std::string& path, const std::string& what,
                          const json& found) const {
  fail(file_, path, "expected " + what + ", found " + describe(found));
}

bool JsonReader::is_comment_key(const std::string& key) {
  return (!key.empty() && key[0] == '_') || key == "comment" || key == "description";
}

void JsonReader::check_keys(const json& obj, const std::string& prefix,
                            std::initializer_list<std::string_view> allowed) const {
  for (const auto& item : obj.items()) {
    const std::string& key = item.key();
    if (is_comment_key(key)) continue;
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
    std::string list;
    for (std::string_view a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
    fail_at(prefix.empty() ? key : prefix + "." + key,
            "unknown key \"" + key + "\", expected one of: " + list +
                " (or a comment key: \"comment\", \"description\", \"_...\")");
  }
}

const json& JsonReader::require(const json& obj, const std::string& prefix, const char* key,
                                const std::string& what) const {
  auto it = obj.find(key);
  std::string path = prefix.empty() ? key : prefix + "." + key;
  if (it == obj.end()) fail_at(path, "missing, expected " + what);
  return *it;
}

float JsonReader::number(const json& j, const std::string& path, Range r) const {
  if (!j.is_number()) expected(path, expected_text(r), j);
  double d = j.get<double>();
  float f = static_cast<float>(d);
  if (!std::isfinite(d) || !std::isfinite(f)) expected(path, "a finite number", j);
  // The range is checked on the number as written too: 1.00000001 rounds to the float 1.
  if (!in_range(d, r) || !in_range(f, r)) expected(path, expected_text(r), j);
  return f;
}

int JsonReader::integer(const json& j, const std::string& path, int lo, int hi) const {
  std::string what = "an integer in " + std::to_string(lo) + ".." + std::to_string(hi);
  if (!j.is_number_integer()) expected(path, what, j);
  bool ok = j.is_number_unsigned() ? j.get<std::uint64_t>() <= std::uint64_t(hi)
                                   : j.get<std::int64_t>() <= hi;
  if (!ok || j.get<std::int64_t>() < lo) expected(path, what, j);
  return static_cast<int>(j.get<std::int64_t>());
}

std::array<float, 2> JsonReader::point(const json& j, const std::string& path) const {
  if (!j.is_array() || j.size() != 2) expected(path, "an [x, y] pair of numbers", j);
  return {number(j[0], path + "[0]", Range::any), number(j[1], path + "[1]", Range::any)};
}

Rgb JsonReader::rgb(const json& j, const std::string& path, Range r) const {
  std::string what = std::string("an array of 3 numbers") + (r == Range::unit     ? " in [0, 1]"
                                                             : r == Range::nonneg ? " >= 0"
                                                                                  : "");
  if (!j.is_array() || j.size() != 3) expected(path, what, j);
  return {number(j[0], path + "[0]", r), number(j[1], path + "[1]", r),
          number(j[2], path + "[2]", r)};
}

std::string JsonReader::string(const json& j, const std::string& path,
                               const std::string& what) const {
  if (!j.is_string()) expected(path, what, j);
  return j.get<std::string>();
}

}  // namespace penumbra::io
