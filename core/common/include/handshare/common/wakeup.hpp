#pragma once
/// A wake-up a real-time thread can post without blocking: any number of posters (the haptic
/// thread, a DDS listener), one waiter (the bridge thread), on a Linux futex.
///
/// Post() bumps a counter and, only while the waiter sleeps on it, makes one FUTEX_WAKE system
/// call: no lock, no allocation, never blocks (the kernel takes its own hash-bucket spinlock
/// for the wake, a few microseconds; the waiter's mutex or condition variable is never taken).
/// WaitUntil() returns at once if something was posted since the last wait returned, else
/// sleeps until a post or the deadline. Posts while the waiter is busy coalesce into one wake.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <ctime>

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace handshare::common {

class Wakeup {
 public:
  using Clock = std::chrono::steady_clock;

  Wakeup() = default;
  Wakeup(const Wakeup&) = delete;
  Wakeup& operator=(const Wakeup&) = delete;

  /// Any thread, real-time safe: wakes the waiter (now, or at once when it next waits).
  void Post() noexcept {
    posted_.fetch_add(1, std::memory_order_release);
    // seq_cst pairs with the waiter's store of sleeping_ then load of posted_ (Dekker): either
    // the waiter sees this post before it sleeps, or this sees it sleeping and wakes it.
    std::atomic_thread_fence(std::memory_order_seq_cst);
    if (sleeping_.load(std::memory_order_relaxed) != 0) {
      syscall(SYS_futex, FutexWord(), FUTEX_WAKE_PRIVATE, 1, nullptr, nullptr, 0);
    }
  }

  /// The one waiting thread: true when woken by a post (since the last call that returned
  /// true), false at the deadline (steady clock: CLOCK_MONOTONIC). Not real-time.
  bool WaitUntil(Clock::time_point deadline) noexcept {
    for (;;) {
      const std::uint32_t now = posted_.load(std::memory_order_acquire);
      if (now != seen_) {
        seen_ = now;
        return true;
      }
      const auto left = deadline - Clock::now();
      if (left <= Clock::duration::zero()) return false;
      sleeping_.store(1, std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_seq_cst);
      if (posted_.load(std::memory_order_relaxed) == seen_) {
        const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(left).count();
        timespec relative{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
        // Sleeps only while the counter still holds the value just read (a post in between
        // makes FUTEX_WAIT return EAGAIN at once).
        syscall(SYS_futex, FutexWord(), FUTEX_WAIT_PRIVATE, seen_, &relative, nullptr, 0);
      }
      sleeping_.store(0, std::memory_order_relaxed);
    }
  }

  /// How many posts so far (any thread; tests and statistics).
  std::uint32_t posts() const noexcept { return posted_.load(std::memory_order_relaxed); }

 private:
  static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t) &&
                    std::atomic<std::uint32_t>::is_always_lock_free,
                "the futex word is the atomic's own 32 bits");
  std::uint32_t* FutexWord() noexcept { return reinterpret_cast<std::uint32_t*>(&posted_); }

  alignas(64) std::atomic<std::uint32_t> posted_{0};
  std::atomic<std::uint32_t> sleeping_{0};
  std::uint32_t seen_ = 0;  // the waiter's: posted_ when it last returned true
};

}  // namespace handshare::common
