// Large arrays on 2 MiB pages where the kernel allows it (transparent huge pages in "always" or
// "madvise" mode). First touching a fresh 48 MB result (a 2048^2 fluence) then takes 24 page
// faults instead of 12,000, which on the development machine's virtual machine cost 0.14-0.21 s,
// more than some methods take to fill it (docs/PERFORMANCE.md).
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace penumbra {

// Advises the 2 MiB-aligned part of [p, p + bytes) as huge pages (nothing for small ranges).
inline void advise_huge_pages(void* p, std::size_t bytes) {
  constexpr std::uintptr_t kHuge = std::uintptr_t(2) << 20;
  const std::uintptr_t at = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t begin = (at + kHuge - 1) & ~(kHuge - 1), end = (at + bytes) & ~(kHuge - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
}

// Makes room for n elements, on huge pages when the vector must grow to hold them.
template <class T>
void reserve_huge(std::vector<T>& v, std::size_t n) {
  if (v.capacity() >= n) return;
  v.reserve(n);
  advise_huge_pages(v.data(), n * sizeof(T));
}

}  // namespace penumbra
