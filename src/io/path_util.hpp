// Small path helpers shared by the image readers and writers.
#pragma once

#include <cctype>
#include <filesystem>
#include <string>

namespace penumbra::io {

// The extension of `path` with its dot, lower-cased (".png"); empty when there is none.
inline std::string lowercase_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace penumbra::io
