#include "handshare/haptic/haptic_loop.hpp"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "handshare/common/clock.hpp"

namespace handshare::haptic {

namespace {
/// Posted for "no renderer", so that nullptr in the mailbox means empty. Never called.
class NoRenderer final : public ForceRenderer {
 public:
  void Render(double, double, std::uint64_t, const DeviceReading&, std::array<Eigen::Vector3d, kFingers>&) noexcept override {}
};
NoRenderer no_renderer;

bool AllFinite(const DeviceReading& r) noexcept {
  if (!r.p_WH.allFinite() || !r.q_WH_wxyz.allFinite()) return false;
  for (int i = 0; i < kFingers; ++i) {
    if (HasFinger(r.finger_mask, i) && !r.p_WE[i].allFinite()) return false;
  }
  return true;
}
}  // namespace

namespace {
ForceSafetyConfig SafetyFor(const HapticLoopConfig& c, const DeviceCapabilities& caps) {
  ForceSafetyConfig s = c.safety;
  s.period = std::chrono::duration<double>(1.0 / c.rate_Hz);
  s.max_force_N = std::min(s.max_force_N, caps.max_fingertip_force_N);
  return s;
}
}  // namespace

HapticLoop::HapticLoop(Device& device, HapticLoopConfig config)
    : device_(device),
      config_(config),
      caps_(device.capabilities()),
      safety_(SafetyFor(config, caps_)) {
  for (auto& f : f_E_W_) f.setZero();
  // Eigen leaves vectors uninitialised: the impulse sums from zero, and the first step adds the
  // "previous" command, which is none.
  for (auto& j : impulse_E_W_Ns_) j.setZero();
  for (auto& f : safety_out_.f_E_W) f.setZero();
}

HapticLoop::~HapticLoop() { Stop(); }

bool HapticLoop::Start() {
  running_.store(true);
  start_ = common::PeriodicLoop::Clock::now();  // before the thread: it reads start_
  thread_ = std::thread([this] { ThreadMain(); });
  if (!config_.realtime_priority) return true;
  sched_param param{};
  param.sched_priority = sched_get_priority_max(SCHED_FIFO) / 2;
  return pthread_setschedparam(thread_.native_handle(), SCHED_FIFO, &param) == 0;
}

double HapticLoop::now_s() const noexcept {
  return std::chrono::duration<double>(common::PeriodicLoop::Clock::now() - start_).count();
}

std::string HapticLoop::FaultCauses() const {
  static constexpr const char* kNames[kFaultCauses] = {"device reading invalid", "device reading not finite",
                                                       "device reading stale", "force or fingertip not finite",
                                                       "fingertip out of range", "fingertip jump"};
  std::string out;
  for (int c = 0; c < kFaultCauses; ++c) {
    const std::uint64_t n = fault_causes_[c].load(std::memory_order_relaxed);
    if (n == 0) continue;
    if (!out.empty()) out += ", ";
    out += std::string(kNames[c]) + " " + std::to_string(n);
  }
  return out;
}

void HapticLoop::Stop() {
  running_.store(false);
  if (thread_.joinable()) thread_.join();
}

void HapticLoop::SetRenderer(std::shared_ptr<ForceRenderer> renderer) {
  ForceRenderer* const post = renderer ? renderer.get() : &no_renderer;
  posted_.push_back({std::move(renderer), numbered_ + 1});  // owned before the haptic thread can take it
  if (pending_.exchange(post, std::memory_order_release) == nullptr) {
    ++numbered_;  // the slot was empty: the previous post was taken
  } else {
    // The previous post (the entry before this one) came back untaken: free it, and this post
    // is the next take instead.
    posted_.erase(posted_.end() - 2);
    posted_.back().number = numbered_;
  }
  CollectRetired();
}

void HapticLoop::CollectRetired() {
  const std::uint64_t in_use = adopted_.load(std::memory_order_acquire);
  const auto first_kept = std::find_if(posted_.begin(), posted_.end(),
                                       [&](const Posted& p) { return p.number >= in_use; });
  posted_.erase(posted_.begin(), first_kept);
}

void HapticLoop::Step(double t_s) noexcept {
  // Only this thread empties the slot, so a slot seen full is still full at the exchange.
  if (pending_.load(std::memory_order_relaxed) != nullptr) {
    ForceRenderer* const taken = pending_.exchange(nullptr, std::memory_order_acquire);
    renderer_ = taken == &no_renderer ? nullptr : taken;
    if (adoption_hook_ != nullptr) adoption_hook_(adoption_hook_arg_);
    adopted_.store(adopted_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }
  const double dt_s = last_t_s_ < 0.0 ? 1.0 / config_.rate_Hz : std::max(0.0, t_s - last_t_s_);
  last_t_s_ = t_s;
  const double world_dt_s = std::min(dt_s, config_.max_world_step_periods / config_.rate_Hz);

  // 1. Read and check the device: invalid, non-finite or stale data is a fault.
  device_.Read(t_s, reading_);
  const std::uint64_t now_ns = common::SteadyNowNs();
  const bool stale = reading_.stamp_ns != 0 && now_ns > reading_.stamp_ns &&
                     static_cast<double>(now_ns - reading_.stamp_ns) * 1e-9 > config_.stale_after_s;
  const bool reading_finite = AllFinite(reading_);
  const bool device_fault = !reading_.valid || !reading_finite || stale;

  // 2. Contacts and controls: the forces the world asks for.
  for (auto& f : f_E_W_) f.setZero();
  if (renderer_ != nullptr) {
    if (device_fault) {
      renderer_->ReleaseAll();
    } else {
      renderer_->Render(t_s, world_dt_s, now_ns, reading_, f_E_W_);
    }
  }
  // A finger the device lacks gets no force, whatever asked for one.
  for (int i = 0; i < kFingers; ++i) {
    if (!HasFinger(reading_.finger_mask, i)) f_E_W_[i].setZero();
  }

  // 3. Safety: clamp, passivity, rate bound; a fault ramps the force to zero.
  safety_in_.device_fault = device_fault;
  safety_in_.elapsed_s = dt_s;
  for (int i = 0; i < kFingers; ++i) {
    safety_in_.finger[i].f_desired_E_W = f_E_W_[i];
    safety_in_.finger[i].p_WE = reading_.p_WE[i];
    safety_in_.finger[i].fault = false;
  }
  // The force commanded at the previous step was held until now.
  for (int i = 0; i < kFingers; ++i) impulse_E_W_Ns_[i] += safety_out_.f_E_W[i] * dt_s;
  safety_.Step(safety_in_, safety_out_);
  const bool fault = device_fault || safety_out_.any_fault;
  if (fault) {
    faults_.fetch_add(1, std::memory_order_relaxed);
    std::uint8_t bits = 0;
    for (const auto& f : safety_out_.finger) bits |= f.fault_bits;
    const bool cause[kFaultCauses] = {!reading_.valid, !reading_finite, stale, (bits & kFaultNonFinite) != 0,
                                      (bits & kFaultOutOfRange) != 0, (bits & kFaultJump) != 0};
    for (int c = 0; c < kFaultCauses; ++c) {
      if (cause[c]) fault_causes_[c].fetch_add(1, std::memory_order_relaxed);
    }
  }
  rate_limited_steps_.store(safety_.rate_limited_steps(), std::memory_order_relaxed);
  device_.Command(safety_out_.f_E_W);

  HapticSnapshot& s = snapshots_.WriteSlot();
  s.seq = ++seq_;
  s.stamp_ns = now_ns;
  s.t_s = t_s;
  s.fault = fault;
  s.finger_mask = reading_.finger_mask;
  s.fingertip_radius_m = caps_.fingertip_radius_m;
  for (int k = 0; k < 3; ++k) s.p_WH_m[k] = device_fault ? 0.0 : reading_.p_WH[k];
  for (int k = 0; k < 4; ++k) s.q_WH_wxyz[k] = device_fault ? (k == 0 ? 1.0 : 0.0) : reading_.q_WH_wxyz[k];
  for (int j = 0; j < common::kHandJoints; ++j) s.q_hand_rad[j] = device_fault ? 0.0 : reading_.q_hand_rad[j];
  for (int j = 0; j < common::kArmJoints; ++j) s.q_arm_rad[j] = device_fault ? 0.0 : reading_.q_arm_rad[j];
  for (int i = 0; i < kFingers; ++i) {
    for (int k = 0; k < 3; ++k) {
      s.p_WE_m[i][k] = device_fault ? 0.0 : reading_.p_WE[i][k];
      s.f_E_W_N[i][k] = safety_out_.f_E_W[i][k];
      s.impulse_E_W_Ns[i][k] = impulse_E_W_Ns_[i][k];
    }
  }
  snapshots_.Publish();
}

void HapticLoop::ThreadMain() {
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(std::llround(1e9 / config_.rate_Hz)));
  common::PeriodicLoop loop(period);
  const int stats_every = std::max(1, static_cast<int>(config_.rate_Hz / 10.0));
  while (running_.load(std::memory_order_relaxed)) {
    const auto now = loop.WaitNext();
    Step(std::chrono::duration<double>(now - start_).count());
    loop.EndStep();
    if (loop.stats().steps % static_cast<std::uint64_t>(stats_every) == 0) stats_.Write(loop.stats());
  }
  stats_.Write(loop.stats());
}

}  // namespace handshare::haptic
