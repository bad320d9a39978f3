// Reading JSON documents with messages that name the file and the JSON path of the offending
// value ("scene.json: shapes[3].radius: expected a number > 0, found -2"): the scene loader's
// reader, shared with the other JSON inputs (the painter's stroke files).
#pragma once

#include <array>
#include <cstdint>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "penumbra/image.hpp"

namespace penumbra::io {

// Internal only: thrown by the readers and checkers, turned into an Error at the API boundary.
struct JsonFailure {
  std::string message;
};

[[noreturn]] void fail(const std::string& file, const std::string& path, const std::string& what);

// Shortest text that reads back as the same number ("-0.1", "16385", "inf", "nan").
std::string format_number(float v);
std::string format_number(double v);
// A computed quantity as a person reads it: three significant digits ("3.4e+38", "41700").
std::string format_rounded(double v);
// Bytes in MiB as messages give them ("775 MiB").
std::string format_mib(std::uint64_t bytes);

// Parses JSON text of `file`. A syntax error throws JsonFailure "file: line L, column C: invalid
// JSON: ..."; a number beyond the double range "file: path: expected a finite number, found
// 1e999 (out of range)".
nlohmann::json parse_json(std::string_view text, const std::string& file);

// What a JSON value is, for "found ..." in messages.
std::string describe(const nlohmann::json& j);

// Value ranges.
enum class Range { any, nonneg, positive, unit };
const char* expected_text(Range r);
bool in_range(double v, Range r);

// Walks a document of `file`; every check that fails throws JsonFailure.
class JsonReader {
 public:
  using json = nlohmann::json;
  explicit JsonReader(std::string file) : file_(std::move(file)) {}
  const std::string& file() const { return file_; }

  [[noreturn]] void fail_at(const std::string& path, const std::string& what) const;
  [[noreturn]] void expected(const std::string& path, const std::string& what,
                             const json& found) const;
  static bool is_comment_key(const std::string& key);
  // Rejects keys that are neither known nor comments, so a typo is never silently ignored.
  void check_keys(const json& obj, const std::string& prefix,
                  std::initializer_list<std::string_view> allowed) const;
  const json& require(const json& obj, const std::string& prefix, const char* key,
                      const std::string& what) const;
  // A finite number that fits a float, in range as written and as a float.
  float number(const json& j, const std::string& path, Range r) const;
  // An integer in [lo, hi].
  int integer(const json& j, const std::string& path, int lo, int hi) const;
  std::array<float, 2> point(const json& j, const std::string& path) const;
  Rgb rgb(const json& j, const std::string& path, Range r) const;
  std::string string(const json& j, const std::string& path, const std::string& what) const;

 private:
  std::string file_;
};

}  // namespace penumbra::io
