// 64-bit FNV-1a over the bytes it is fed: the fingerprint of a scene that a study's cache (2D)
// and a baked atlas (3D) are checked against.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace penumbra {

struct Fnv1a {
  std::uint64_t h = 1469598103934665603ull;
  void bytes(const void* p, std::size_t n) {
    const auto* c = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ c[i]) * 1099511628211ull;
  }
  template <class T>
  void value(const T& v) {
    bytes(&v, sizeof v);
  }
  // The size, then the elements.
  template <class T>
  void array(const std::vector<T>& v) {
    value(v.size());
    if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
  }
};

}  // namespace penumbra
