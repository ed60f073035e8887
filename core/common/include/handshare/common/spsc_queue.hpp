#pragma once
/// Bounded lock-free queue for one producer thread and one consumer thread, for events that
/// must not be lost (control events from the haptic thread, commands to it). Capacity is fixed
/// at compile time; Push fails instead of allocating when full. Real-time safe on both ends.
#include <array>
#include <atomic>
#include <cstddef>
#include <type_traits>

namespace handshare::common {

template <class T, std::size_t kCapacity>
class SpscQueue {
  static_assert(std::is_trivially_copyable_v<T>, "SpscQueue carries fixed-size events");
  static_assert(kCapacity >= 2 && (kCapacity & (kCapacity - 1)) == 0,
                "capacity must be a power of two");

 public:
  /// Producer only. Returns false (and drops nothing already queued) when full.
  bool Push(const T& value) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) == kCapacity) return false;
    items_[head & (kCapacity - 1)] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Consumer only. Returns false when empty.
  bool Pop(T& out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    out = items_[tail & (kCapacity - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  static constexpr std::size_t capacity() noexcept { return kCapacity; }

 private:
  std::array<T, kCapacity> items_{};
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::atomic<std::size_t> tail_{0};
};

}  // namespace handshare::common
