// libFuzzer target: the mesh readers (OBJ, glTF, GLB) on arbitrary bytes. The first byte picks
// the format; the rest is written to a file of that extension (the readers take paths, as the
// scene loader gives them) and read. Any outcome but a clean Error or a mesh is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "io/json_reader.hpp"
#include "spaceland/scene/mesh_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kExtensions[] = {".obj", ".gltf", ".glb"};
  const std::string path = "fuzz-mesh-" + std::to_string(getpid()) + kExtensions[data[0] % 3];
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 1 && std::fwrite(data + 1, 1, size - 1, f) != size - 1) std::abort();
  std::fclose(f);
  try {
    const penumbra::spaceland::MeshFile mesh = penumbra::spaceland::read_mesh_file(
        path, "fuzz.json", "objects[0].file", std::uint64_t(256) << 20);
    // What the reader returns must be consistent: indices and materials in range.
    const auto& m = mesh.mesh;
    if (m.materials.size() != m.triangles.size()) std::abort();
    if (!m.normals.empty() && m.normals.size() != m.positions.size()) std::abort();
    if (!m.uvs.empty() && m.uvs.size() != m.positions.size()) std::abort();
    for (const auto& t : m.triangles)
      for (std::uint32_t i : t)
        if (i >= m.positions.size()) std::abort();
    for (std::uint32_t k : m.materials)
      if (k >= mesh.materials.size()) std::abort();
  } catch (const penumbra::io::JsonFailure&) {
  }
  std::remove(path.c_str());
  return 0;
}
