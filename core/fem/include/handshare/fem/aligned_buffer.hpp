#pragma once
/// @file
/// A std::vector whose storage starts on a 64-byte boundary (one cache line, one AVX-512
/// register), for the streamed surface-field tables. Allocation happens only where the vector
/// grows (offline); the real-time kernels only read it.

#include <cstddef>
#include <new>
#include <vector>

namespace handshare::fem {

template <class T>
struct CacheLineAllocator {
  using value_type = T;
  CacheLineAllocator() noexcept = default;
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) noexcept {}  // NOLINT: rebinding
  T* allocate(std::size_t n) {
    return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t{64}));
  }
  void deallocate(T* p, std::size_t) noexcept { ::operator delete(p, std::align_val_t{64}); }
  template <class U>
  bool operator==(const CacheLineAllocator<U>&) const noexcept {
    return true;
  }
};

/// Vector of T aligned to 64 bytes.
template <class T>
using AlignedVector = std::vector<T, CacheLineAllocator<T>>;

}  // namespace handshare::fem
