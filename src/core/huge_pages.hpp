// Large arrays on 2 MiB pages where the kernel allows it (transparent huge pages in "always" or
// "madvise" mode). First touching a fresh 48 MB result (a 2048^2 fluence) then takes 24 page
// faults instead of 12,000, which on the development machine's virtual machine cost 0.14-0.21 s,
// more than some methods take to fill it (docs/PERFORMANCE.md).
#pragma once

#include <sys/mman.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
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

// v.assign(n, value), on huge pages when the vector must grow to hold n.
template <class T>
void assign_huge(std::vector<T>& v, std::size_t n, const T& value = T{}) {
  reserve_huge(v, n);
  v.assign(n, value);
}

// An uninitialised array that only grows (a solver's workspace keeps one per buffer, so its
// steady state allocates nothing). Large ones are aligned to and
// advised as 2 MiB pages: a first solve then takes 512 times fewer page faults (they cost more
// than the arithmetic in a virtual machine), and the merges' strided columns fewer TLB misses.
struct FreeDeleter {
  void operator()(void* p) const { std::free(p); }
};

template <class T>
struct HugeArray {
  std::unique_ptr<T, FreeDeleter> p;
  std::size_t n = 0;
  T* ensure(std::size_t m) {
    static_assert(std::is_trivially_default_constructible_v<T>);
    if (n >= m) return p.get();
    p.reset();
    constexpr std::size_t kHuge = std::size_t(2) << 20;
    const std::size_t bytes = std::max<std::size_t>(m * sizeof(T), 1);
    const std::size_t align = bytes >= 2 * kHuge ? kHuge : 64;
    void* mem = std::aligned_alloc(align, (bytes + align - 1) / align * align);
    if (!mem) throw std::bad_alloc();
    if (align == kHuge) madvise(mem, (bytes + align - 1) / align * align, MADV_HUGEPAGE);
    p.reset(static_cast<T*>(mem));
    n = m;
    return p.get();
  }
  void release() { p.reset(), n = 0; }
};

}  // namespace penumbra
