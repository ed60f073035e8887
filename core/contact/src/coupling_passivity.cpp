#include "handshare/contact/coupling_passivity.hpp"

#include <algorithm>
#include <cmath>

namespace handshare::contact {

namespace {

// Below this change of the imposed displacement a step says nothing about the stiffness.
constexpr double kStiffnessProbe_m = 5e-6;
// The largest stiffness believed (a fingertip patch on the stiffest scene body is ~1e3 N/m).
constexpr double kMaxStiffness_N_per_m = 1e5;
// Energy below this is rounding (a fingertip's work over one step is ~1e-6 J and up).
constexpr double kRounding_J = 1e-12;
// A held-back displacement within this of its target has caught up.
constexpr double kCaughtUp_m = 1e-7;
// The peer is still when its samples stay within kStill_m of one another for kStillAfter_ns
// (most of one deadband keepalive, session/contact_deadband.hpp): slower than about 0.2 mm/s.
// Absolute, not a Weber fraction: at the turn of a slow swing a relative band would call the
// peer still for longer than a keepalive, and a grant at every turn could feed the swing.
constexpr double kStill_m = 20e-6;
constexpr std::uint64_t kStillAfter_ns = 90'000'000;

}  // namespace

int CouplingPassivity::Find(std::uint64_t user_key, std::int32_t finger, std::int32_t object) const noexcept {
  for (int i = 0; i < kMaxChannels; ++i) {
    const Channel& c = channels_[static_cast<std::size_t>(i)];
    if (c.open && c.user_key == user_key && c.finger == finger && c.object == object) return i;
  }
  return -1;
}

double CouplingPassivity::observer_J(std::uint64_t user_key, std::int32_t finger, std::int32_t object) const noexcept {
  const int i = Find(user_key, finger, object);
  if (i < 0) return 0.0;
  const Channel& c = channels_[static_cast<std::size_t>(i)];
  return c.e_tx + c.e_granted - c.e_rx;
}

void CouplingPassivity::BeginStep(double dt_s, double catch_up_rate_per_s) noexcept {
  const bool ok = std::isfinite(dt_s) && dt_s > 0.0;
  dt_s_ = ok ? dt_s : 0.0;
  max_step_m_ = ok ? kMaxSpeed_m_per_s * dt_s : 0.0;
  catch_up_rate_per_s_ = std::isfinite(catch_up_rate_per_s) && catch_up_rate_per_s > 0.0 ? catch_up_rate_per_s : 0.0;
  num_admitted_ = 0;
  for (Channel& c : channels_) c.seen = false;
}

// Admit's stages: the contact's channel, the peer's end (what its samples did), this end (the
// displacement the solve may impose), then the channel's state for the next step.
void CouplingPassivity::Admit(const PeerContact& sent, FingerContact& input) noexcept {
  if (num_admitted_ >= kMaxChannels) return;  // more than the renderer hands in: passed, unobserved
  std::int16_t& slot = admitted_[static_cast<std::size_t>(num_admitted_++)];
  slot = -1;
  if (!AsVector(input.u_O_m).allFinite()) return;
  Channel* ch = ChannelOf(sent);
  if (ch == nullptr) return;
  if (ch->seen) return;  // the same contact twice in one set: the first one is the channel's
  ch->seen = true;
  slot = static_cast<std::int16_t>(ch - channels_.data());

  ObserveSample(*ch, sent);
  const bool still = ch->still_since_ns != 0 && sent.received_ns - ch->still_since_ns >= kStillAfter_ns;

  // This end: the displacement the solve will impose, within what the channel has brought.
  const Eigen::Vector3d target = AsVector(input.u_O_m);
  const Eigen::Vector3d u = enabled_ ? Limit(*ch, target, still) : target;
  if (ch->held && (target - u).norm() <= kCaughtUp_m) ch->held = false;
  ch->target_prev = target;
  input.u_O_m = ToVec3(u);
  ch->du = u - ch->u_imposed;
  ch->u_imposed = u;
}

CouplingPassivity::Channel* CouplingPassivity::ChannelOf(const PeerContact& sent) noexcept {
  const int found = Find(sent.user_key, sent.contact.finger, sent.contact.object);
  if (found >= 0) return &channels_[static_cast<std::size_t>(found)];
  for (Channel& c : channels_) {
    if (!c.open) {
      c = Channel{};
      c.open = true;
      c.user_key = sent.user_key;
      c.finger = sent.contact.finger;
      c.object = sent.contact.object;
      ++stats_.channels_total;
      return &c;
    }
  }
  return nullptr;
}

// The peer's end: the work its sample path did on its body (the body got minus the force on
// the fingertip), once per sample.
void CouplingPassivity::ObserveSample(Channel& ch, const PeerContact& sent) noexcept {
  if (sent.received_ns == ch.sample_ns) return;
  // f: the force on the peer's fingertip (minus the force on the body).
  const Eigen::Vector3d u = AsVector(sent.contact.u_O_m), f = -AsVector(sent.contact.f_O_N);
  if (u.allFinite() && f.allFinite()) {
    ch.e_tx += std::max(0.0, -0.5 * (f + ch.f_sent).dot(u - ch.u_sent));
    ch.u_sent = u;
    ch.f_sent = f;
    // The peer is still once its samples have stayed within kStill_m of one another for
    // kStillAfter_ns (a deadbanded still hand sends a keepalive every 100 ms).
    if (ch.still_since_ns == 0 || (u - ch.u_still).norm() > kStill_m) {
      ch.u_still = u;
      ch.still_since_ns = sent.received_ns;
    }
  }
  ch.sample_ns = sent.received_ns;
}

// A sample's jump is taken at no more than a fingertip's speed: the step's energy is then
// predicted to within (1/2) k (v dt)^2 even before the contact's stiffness is known.
// After a hold, the lag closes at the fade's rate (the speed at which a peer's contact of
// this size fades in or out), not at a fingertip's: the other hand feels a ramp, not a step.
// The sample's own change still passes at a fingertip's speed.
Eigen::Vector3d CouplingPassivity::Limit(Channel& ch, const Eigen::Vector3d& target, bool still) noexcept {
  auto clamped = [](const Eigen::Vector3d& v, double limit) -> Eigen::Vector3d {
    const double d = v.norm();
    return d > limit ? Eigen::Vector3d((limit / d) * v) : v;
  };
  Eigen::Vector3d to = target - ch.u_imposed;
  if (ch.held) {
    const double catch_up_m = catch_up_rate_per_s_ * std::max(target.norm(), ch.u_imposed.norm()) * dt_s_;
    to = clamped(target - ch.target_prev, max_step_m_) + clamped(ch.target_prev - ch.u_imposed, catch_up_m);
  }
  Eigen::Vector3d u = ch.u_imposed + clamped(to, max_step_m_);
  const Eigen::Vector3d& F = ch.force;
  auto predicted = [&](const Eigen::Vector3d& d) { return F.dot(d) + 0.5 * ch.k * d.squaredNorm(); };
  const double budget = ch.e_tx + ch.e_granted - ch.e_rx;
  const Eigen::Vector3d du = u - ch.u_imposed;
  const double want = predicted(du);
  // (Rounding: on a linear body without delay the prediction equals the budget's increment.)
  const bool over_budget = want > budget + kRounding_J + 1e-9 * std::abs(want);
  if (over_budget && ch.held && still) {
    // The peer has stopped and the local copy still lags: the lag closes (at the fade's rate
    // above), granted beyond the budget so that both copies come to one shape. Bounded by the
    // work of closing the lag, once per stop; a swing never stops, so it is never granted one.
    const double grant = want - std::max(budget, 0.0);
    ch.e_granted += grant;
    stats_.energy_granted_J += grant;
    ++stats_.granted_still;
  } else if (over_budget) {
    u = ScaledToBudget(ch, du, budget);
    ch.held = true;
    ++stats_.held_back;
    stats_.drift_max_m = std::max(stats_.drift_max_m, (target - u).norm());
  }
  return u;
}

// Scale the change: k a^2 |du|^2 / 2 + (F . du) a = budget, the root in [0, 1]. With no
// budget left (a prediction fell short by a step's error), nothing that puts energy in
// passes until the peer's samples bring more; a release always passes.
Eigen::Vector3d CouplingPassivity::ScaledToBudget(const Channel& ch, const Eigen::Vector3d& du,
                                                  double budget) const noexcept {
  const double room = std::max(budget, 0.0);
  const double a = 0.5 * ch.k * du.squaredNorm(), b = ch.force.dot(du);
  double alpha = 0.0;
  if (a > 0.0) {
    alpha = (-b + std::sqrt(std::max(0.0, b * b + 4.0 * a * room))) / (2.0 * a);
  } else if (b > 0.0) {
    alpha = room / b;
  }
  alpha = std::clamp(alpha, 0.0, 1.0);
  return ch.u_imposed + alpha * du;
}

void CouplingPassivity::Observe(std::span<const Eigen::Vector3d> force_on_body_O) noexcept {
  if (num_admitted_ > 0) ++stats_.steps;
  for (std::int32_t i = 0; i < num_admitted_; ++i) {
    const std::int16_t slot = admitted_[static_cast<std::size_t>(i)];
    if (slot < 0) continue;
    Channel& ch = channels_[static_cast<std::size_t>(slot)];
    Eigen::Vector3d F = static_cast<std::size_t>(i) < force_on_body_O.size() ? force_on_body_O[static_cast<std::size_t>(i)]
                                                                             : Eigen::Vector3d::Zero();
    if (!F.allFinite()) F.setZero();
    const Eigen::Vector3d& du = ch.du;
    ch.e_rx += std::max(0.0, 0.5 * (ch.force + F).dot(du));
    const double dd = du.squaredNorm();
    if (dd > kStiffnessProbe_m * kStiffnessProbe_m) {
      const double k = (F - ch.force).dot(du) / dd;
      ch.k = std::clamp(std::max(ch.k, k), 0.0, kMaxStiffness_N_per_m);
    }
    ch.force = F;
    stats_.observer_min_J = std::min(stats_.observer_min_J, ch.e_tx + ch.e_granted - ch.e_rx);
  }
  double tx = closed_tx_, rx = closed_rx_;
  for (Channel& c : channels_) {
    if (!c.open) continue;
    if (!c.seen) {  // the contact left the solve (lifted, faded out): its channel ends
      closed_tx_ += c.e_tx;
      closed_rx_ += c.e_rx;
      tx += c.e_tx;
      rx += c.e_rx;
      c.open = false;
      continue;
    }
    tx += c.e_tx;
    rx += c.e_rx;
  }
  stats_.energy_sent_J = tx;
  stats_.energy_received_J = rx;
}

}  // namespace handshare::contact
