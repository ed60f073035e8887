#include "handshare/haptic/haptic_loop.hpp"

#include <pthread.h>
#include <sched.h>

#include <cmath>

#include "handshare/common/clock.hpp"

namespace handshare::haptic {

namespace {
bool AllFinite(const DeviceReading& r) noexcept {
  if (!r.p_WH.allFinite() || !r.q_WH_wxyz.allFinite()) return false;
  for (const auto& p : r.p_WE) {
    if (!p.allFinite()) return false;
  }
  return true;
}
}  // namespace

HapticLoop::HapticLoop(Device& device, HapticLoopConfig config)
    : device_(device), config_(config), caps_(device.capabilities()) {
  for (auto& f : f_E_W_) f.setZero();
}

HapticLoop::~HapticLoop() { Stop(); }

bool HapticLoop::Start() {
  running_.store(true);
  thread_ = std::thread([this] { ThreadMain(); });
  if (!config_.realtime_priority) return true;
  sched_param param{};
  param.sched_priority = sched_get_priority_max(SCHED_FIFO) / 2;
  return pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &param) == 0;
}

void HapticLoop::Stop() {
  running_.store(false);
  if (thread_.joinable()) thread_.join();
}

void HapticLoop::Step(double t_s) noexcept {
  device_.Read(t_s, reading_);
  const bool fault = !reading_.valid || !AllFinite(reading_);
  if (fault) faults_.fetch_add(1, std::memory_order_relaxed);

  // Contact rendering fills f_E_W_ here (later layers). A fault means zero force, always.
  for (auto& f : f_E_W_) {
    if (fault || !f.allFinite()) f.setZero();
    const double n = f.norm();
    if (n > caps_.max_fingertip_force_N) f *= caps_.max_fingertip_force_N / n;
  }
  device_.Command(f_E_W_);

  HapticSnapshot& s = snapshots_.WriteSlot();
  s.seq = ++seq_;
  s.stamp_ns = common::SteadyNowNs();
  s.t_s = t_s;
  s.fault = fault;
  s.fingertip_radius_m = caps_.fingertip_radius_m;
  for (int k = 0; k < 3; ++k) s.p_WH_m[k] = fault ? 0.0 : reading_.p_WH[k];
  for (int k = 0; k < 4; ++k) s.q_WH_wxyz[k] = fault ? (k == 0 ? 1.0 : 0.0) : reading_.q_WH_wxyz[k];
  for (int i = 0; i < kFingers; ++i) {
    for (int k = 0; k < 3; ++k) {
      s.p_WE_m[i][k] = fault ? 0.0 : reading_.p_WE[i][k];
      s.f_E_W_N[i][k] = f_E_W_[i][k];
    }
  }
  snapshots_.Publish();
}

void HapticLoop::ThreadMain() {
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(std::llround(1e9 / config_.rate_Hz)));
  common::PeriodicLoop loop(period);
  const auto start = common::PeriodicLoop::Clock::now();
  const int stats_every = std::max(1, static_cast<int>(config_.rate_Hz / 10.0));
  while (running_.load(std::memory_order_relaxed)) {
    const auto now = loop.WaitNext();
    Step(std::chrono::duration<double>(now - start).count());
    loop.EndStep();
    if (loop.stats().steps % static_cast<std::uint64_t>(stats_every) == 0) stats_.Write(loop.stats());
  }
  stats_.Write(loop.stats());
}

}  // namespace handshare::haptic
