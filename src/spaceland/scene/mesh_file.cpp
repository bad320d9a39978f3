// read_mesh_file: dispatch by extension and the messages every mesh-file failure gets.
#include "spaceland/scene/mesh_file.hpp"

#include <stb/stb_image.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <new>
#include <system_error>

#include "io/json_reader.hpp"
#include "io/path_util.hpp"
#include "spaceland/scene/mesh_reader.hpp"

namespace penumbra::spaceland {

namespace mesh_detail {

namespace {

// "62914561 bytes (60.0 MiB)": exact, so that a need just past the limit does not read as equal.
std::string bytes_text(double bytes) {
  char mib[32];
  std::snprintf(mib, sizeof mib, "%.1f", bytes / double(1 << 20));
  return (bytes < 1.8e19 ? std::to_string(std::uint64_t(bytes)) : io::format_rounded(bytes)) +
         " bytes (" + mib + " MiB)";
}

}  // namespace

void Budget::take(std::uint64_t bytes, const std::string& what) {
  if (bytes > max_ || used_ > max_ - bytes)
    mesh_fail(what + " need " + bytes_text(double(used_) + double(bytes)) +
              " in all, more than the memory limit of " + bytes_text(double(max_)));
  used_ += bytes;
}

std::uint64_t mesh_bytes(std::uint64_t vertices, bool normals, bool uvs, std::uint64_t triangles) {
  const std::uint64_t per_vertex = sizeof(Vec3) * (normals ? 2 : 1) + (uvs ? 8 : 0);
  const std::uint64_t per_triangle = 3 * sizeof(std::uint32_t) + sizeof(std::uint32_t);
  // Saturates rather than wraps: counts come from the file.
  const long double total =
      (long double)vertices * per_vertex + (long double)triangles * per_triangle;
  return total >= 1.8e19L ? UINT64_MAX : std::uint64_t(total);
}

Texture decode_texture(const unsigned char* bytes, std::size_t length, bool srgb,
                       const std::string& name, Budget& budget) {
  const int size = int(std::min<std::size_t>(length, INT32_MAX));
  int w = 0, h = 0, channels = 0;
  if (!stbi_info_from_memory(bytes, size, &w, &h, &channels) || w <= 0 || h <= 0)
    mesh_fail(name + ": cannot decode the image (" + std::string(stbi_failure_reason()) + ")");
  budget.take(std::uint64_t(w) * std::uint64_t(h) * 3 * sizeof(float),
              "texture " + name + " (" + std::to_string(w) + "x" + std::to_string(h) + ")");
  std::unique_ptr<unsigned char, void (*)(void*)> pixels(
      stbi_load_from_memory(bytes, size, &w, &h, &channels, 3), stbi_image_free);
  if (!pixels)
    mesh_fail(name + ": cannot decode the image (" + std::string(stbi_failure_reason()) + ")");
  Texture t;
  t.width = w;
  t.height = h;
  t.rgb.resize(std::size_t(w) * std::size_t(h) * 3);
  float linear[256];
  for (int c = 0; c < 256; ++c) {
    const double v = c / 255.0;
    linear[c] = float(!srgb ? v : v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
  }
  for (std::size_t k = 0; k < t.rgb.size(); ++k) t.rgb[k] = linear[pixels.get()[k]];
  return t;
}

std::string read_whole_file(const std::string& path, std::uint64_t max_bytes,
                            const std::string& what) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    if (std::filesystem::exists(path, ec)) mesh_fail(what + " is not a regular file");
    mesh_fail(what + " not found (" + path + ")");
  }
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) mesh_fail("cannot read " + what + ": " + ec.message());
  if (size > max_bytes)
    mesh_fail(what + " has " + std::to_string(size) + " bytes, more than the memory limit of " +
              io::format_rounded(double(max_bytes)) + " bytes");
  std::ifstream in(path, std::ios::binary);
  std::string text(size, '\0');
  if (!in || !in.read(text.data(), std::streamsize(size)) || in.gcount() != std::streamsize(size))
    mesh_fail("cannot read " + what + " (" + path + ")");
  return text;
}

Vec3 flat_normal(Vec3 a, Vec3 b, Vec3 c) {
  const Vec3 n = cross(b - a, c - a);
  const float len = length(n);
  if (!(len > 0) || !std::isfinite(len)) return {0, 0, 1};
  return n / len;
}

}  // namespace mesh_detail

namespace {

// read(budget) with every failure as "<scene_file>: <json_path>: <file name>: <what>".
template <class Read>
auto reading(const std::string& file_path, const std::string& scene_file,
             const std::string& json_path, std::uint64_t max_bytes, Read&& read) {
  std::string what;
  try {
    mesh_detail::Budget budget(max_bytes);
    return read(budget);
  } catch (const mesh_detail::MeshError& e) {
    what = e.what;
  } catch (const std::bad_alloc&) {
    what = "out of memory while reading it";
  } catch (const std::exception& e) {
    // The libraries' own exceptions (a JSON parser's, a container's).
    what = std::string("cannot read it: ") + e.what();
  }
  io::fail(scene_file, json_path,
           std::filesystem::path(file_path).filename().string() + ": " + what);
}

}  // namespace

MeshFile read_mesh_file(const std::string& file_path, const std::string& scene_file,
                        const std::string& json_path, std::uint64_t max_bytes) {
  const std::string ext = io::lowercase_extension(file_path);
  return reading(file_path, scene_file, json_path, max_bytes, [&](mesh_detail::Budget& budget) {
    if (ext == ".obj") return mesh_detail::read_obj(file_path, budget);
    if (ext == ".gltf" || ext == ".glb") return mesh_detail::read_gltf(file_path, budget);
    mesh_detail::mesh_fail("unknown mesh file type '" + ext + "' (expected .obj, .gltf or .glb)");
  });
}

GltfCamera read_gltf_camera(const std::string& file_path, int index, const std::string& scene_file,
                            const std::string& json_path, std::uint64_t max_bytes) {
  const std::string ext = io::lowercase_extension(file_path);
  return reading(file_path, scene_file, json_path, max_bytes, [&](mesh_detail::Budget& budget) {
    if (ext != ".gltf" && ext != ".glb")
      mesh_detail::mesh_fail("a camera is read from a glTF file (.gltf or .glb), not '" + ext +
                             "'");
    return mesh_detail::read_gltf_camera(file_path, index, budget);
  });
}

}  // namespace penumbra::spaceland
