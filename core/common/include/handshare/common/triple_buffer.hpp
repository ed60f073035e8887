#pragma once
/// Lock-free latest-value hand-off between exactly one producer thread and one consumer
/// thread (for example the haptic thread and the DDS bridge thread).
///
/// The producer writes into its own slot and publishes it with one atomic exchange; the
/// consumer takes the newest published slot with one atomic exchange. Neither side ever
/// blocks, allocates or waits for the other, so it is safe inside the real-time step.
/// T must be trivially copyable (a fixed-size snapshot).
#include <array>
#include <atomic>
#include <cstdint>
#include <type_traits>

namespace handshare::common {

template <class T>
class TripleBuffer {
  static_assert(std::is_trivially_copyable_v<T>, "TripleBuffer carries fixed-size snapshots");

 public:
  TripleBuffer() = default;
  explicit TripleBuffer(const T& initial) { slots_.fill(initial); }
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  /// Producer only: the slot to fill before Publish(). Real-time safe.
  T& WriteSlot() noexcept { return slots_[write_]; }

  /// Producer only: makes the write slot the newest value. Real-time safe.
  void Publish() noexcept {
    const std::uint8_t prev = middle_.exchange(static_cast<std::uint8_t>(write_ | kFresh),
                                               std::memory_order_acq_rel);
    write_ = prev & kIndexMask;
  }

  /// Producer only: copies value in and publishes it.
  void Write(const T& value) noexcept {
    WriteSlot() = value;
    Publish();
  }

  /// Consumer only: if a value newer than the last one read exists, copies it to out and
  /// returns true; otherwise leaves out unchanged and returns false. Real-time safe.
  bool Read(T& out) noexcept {
    if ((middle_.load(std::memory_order_acquire) & kFresh) == 0) return false;
    const std::uint8_t prev = middle_.exchange(read_, std::memory_order_acq_rel);
    read_ = prev & kIndexMask;
    out = slots_[read_];
    return true;
  }

 private:
  static constexpr std::uint8_t kIndexMask = 0x3;
  static constexpr std::uint8_t kFresh = 0x4;

  std::array<T, 3> slots_{};
  alignas(64) std::atomic<std::uint8_t> middle_{1};  // index of the shared slot + fresh bit
  alignas(64) std::uint8_t write_ = 0;               // producer's private slot
  alignas(64) std::uint8_t read_ = 2;                // consumer's private slot
};

}  // namespace handshare::common
