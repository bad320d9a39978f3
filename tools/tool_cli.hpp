// The command line of every program Penumbra ships besides `penumbra` itself (the tools and the
// benchmarks' own front ends), so that they all behave alike: `--help` (with defaults) and
// `--version` print and exit 0, a usage error prints why and exits 2, and a program that cannot
// write what it was asked to write exits 1 (kCannotWrite) before doing the work.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>

#include "penumbra/version.hpp"

namespace penumbra::tool {

inline constexpr int kCannotWrite = 1, kUsage = 2;

// Parses argv into `app`; returns the exit code when the program should stop now (--help,
// --version: 0; a usage error: kUsage), nothing when it should go on.
inline std::optional<int> parse(CLI::App& app, int argc, char** argv) {
  app.set_version_flag("--version", app.get_name() + " (penumbra " + kVersion + ")");
  app.get_formatter()->column_width(34);
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kUsage;
  }
  return std::nullopt;
}

// An output folder: made if missing, but only inside a folder that exists (a mistyped path
// must not grow a tree of folders). Prints why not and returns false.
inline bool output_folder(const std::string& program, std::filesystem::path dir) {
  if (!dir.has_filename()) dir = dir.parent_path();  // "out/"
  std::error_code ec;
  if (std::filesystem::is_directory(dir, ec)) return true;
  const std::filesystem::path parent =
      dir.has_parent_path() ? dir.parent_path() : std::filesystem::path(".");
  if (!std::filesystem::is_directory(parent, ec)) {
    std::fprintf(stderr, "%s: cannot write into %s: %s is not a folder\n", program.c_str(),
                 dir.string().c_str(), parent.string().c_str());
    return false;
  }
  if (!std::filesystem::create_directory(dir, ec) || ec) {
    std::fprintf(stderr, "%s: cannot create the folder %s: %s\n", program.c_str(),
                 dir.string().c_str(), ec ? ec.message().c_str() : "a file has that name");
    return false;
  }
  return true;
}

}  // namespace penumbra::tool
