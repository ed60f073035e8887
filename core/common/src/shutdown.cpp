#include "handshare/common/shutdown.hpp"

#include <atomic>
#include <csignal>
#include <thread>

namespace handshare::common {

namespace {
std::atomic<bool> g_shutdown{false};
static_assert(std::atomic<bool>::is_always_lock_free, "flag is set from a signal handler");

extern "C" void OnSignal(int) { g_shutdown.store(true); }
}  // namespace

void InstallShutdownHandlers() {
  struct sigaction action {};
  action.sa_handler = OnSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool ShutdownRequested() noexcept { return g_shutdown.load(std::memory_order_relaxed); }

void RequestShutdown() noexcept { g_shutdown.store(true); }

bool SleepUnlessShutdown(std::chrono::nanoseconds d) {
  const auto end = std::chrono::steady_clock::now() + d;
  while (!ShutdownRequested()) {
    const auto now = std::chrono::steady_clock::now();
    if (now >= end) return true;
    std::this_thread::sleep_for(std::min<std::chrono::nanoseconds>(end - now,
                                                                   std::chrono::milliseconds(5)));
  }
  return false;
}

}  // namespace handshare::common
