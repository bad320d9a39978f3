// Owen-scrambled Sobol points (Burley 2020, "Practical Hash-based Owen Scrambling"): a 2D Sobol
// sequence per pair of dimensions, each pair with its own nested uniform scramble and shuffled
// sample order ("padding"). Every point is uniform on [0, 1)^2 (unbiased), and the first 2^k
// points of a pair are stratified in every 2^k elementary interval (error falls faster than
// 1/sqrt(n)). A point depends only on (seed, sample index, pair): the same whatever thread or
// pass computes it.
#pragma once

#include <array>
#include <cstdint>

namespace penumbra::sobol {

inline std::uint32_t reverse_bits(std::uint32_t x) {
  x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
  x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
  x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
  x = ((x >> 8) & 0x00FF00FFu) | ((x & 0x00FF00FFu) << 8);
  return (x >> 16) | (x << 16);
}

// Burley's improved Laine-Karras hash: a permutation that only lets lower bits affect higher
// ones, which on bit-reversed values is an Owen scramble.
inline std::uint32_t laine_karras_permutation(std::uint32_t x, std::uint32_t seed) {
  x += seed;
  x ^= x * 0x6c50b47cu;
  x ^= x * 0xb82f1e52u;
  x ^= x * 0xc7afe638u;
  x ^= x * 0x8d22f6e6u;
  return x;
}

inline std::uint32_t nested_uniform_scramble(std::uint32_t x, std::uint32_t seed) {
  return reverse_bits(laine_karras_permutation(reverse_bits(x), seed));
}

// A 32-bit hash of a 64-bit key (splitmix64's finaliser, folded).
inline std::uint32_t hash(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return std::uint32_t((z ^ (z >> 31)) >> 16);
}

// Sobol's second dimension (primitive polynomial x + 1): v_k = v_{k-1} ^ (v_{k-1} >> 1).
inline std::uint32_t sobol_dimension1(std::uint32_t index) {
  std::uint32_t result = 0, v = 0x80000000u;
  for (; index != 0; index >>= 1, v ^= v >> 1)
    if (index & 1u) result ^= v;
  return result;
}

// To [0, 1): the top 24 bits, so that the float is never rounded up to 1.
inline float to_unit(std::uint32_t x) {
  return float(x >> 8) * 0x1.0p-24f;
}

// Point `index` of the scrambled pair `pair` for the stream `seed` (e.g. a pixel and a user seed
// hashed together).
inline std::array<float, 2> sample_2d(std::uint32_t index, std::uint32_t seed, std::uint32_t pair) {
  const std::uint32_t s = hash((std::uint64_t(seed) << 32) | pair);
  const std::uint32_t shuffled = nested_uniform_scramble(index, s);
  const std::uint32_t x = nested_uniform_scramble(reverse_bits(shuffled), hash(s ^ 0xA511E9B3u));
  const std::uint32_t y =
      nested_uniform_scramble(sobol_dimension1(shuffled), hash(s ^ 0x63D83595u));
  return {to_unit(x), to_unit(y)};
}

}  // namespace penumbra::sobol
