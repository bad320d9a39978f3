// One cascade's radiance: per probe and direction of its octahedral map, RGB. The accessor owns
// the layout, probe-major (a probe's directions side by side): the merges read a probe's 2x2 (or
// 4x4) children of one direction together, and the gathers a probe's whole map, so both stay
// within a probe's few cache lines (docs/PERFORMANCE.md, "The 3D cascade core").
#pragma once

#include <cstdint>
#include <vector>

#include "penumbra/image.hpp"

namespace penumbra::spaceland::cascade {

class RadianceStore {
 public:
  // `probes` probes of a side x side map each, every value `fill`; the memory is kept from one
  // cascade to the next only where it is the same size.
  void assign(std::uint64_t probes, int side, Rgb fill = {}) {
    side_ = side;
    directions_ = std::size_t(side) * std::size_t(side);
    const std::size_t n = std::size_t(probes) * directions_;
    // The old values go first, so that old and new arrays are never held at once, and a store
    // holds no more than its cascade (the memory estimate counts each cascade's own size).
    if (n != data_.capacity()) data_ = {};
    data_.assign(n, fill);
  }
  const Rgb& at(std::uint64_t probe, std::size_t d) const {
    return data_[std::size_t(probe) * directions_ + d];
  }
  // Probe q's directions, index v * side + u.
  Rgb* probe(std::uint64_t q) { return data_.data() + std::size_t(q) * directions_; }
  const Rgb* probe(std::uint64_t q) const { return data_.data() + std::size_t(q) * directions_; }

  int side() const { return side_; }

  // What a store of that size holds.
  static std::uint64_t bytes(std::uint64_t probes, int side) {
    return probes * std::uint64_t(side) * std::uint64_t(side) * sizeof(Rgb);
  }

 private:
  std::vector<Rgb> data_;
  int side_ = 0;
  std::size_t directions_ = 0;
};

}  // namespace penumbra::spaceland::cascade
