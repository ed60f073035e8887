// Control base (frames, force clamp, miss detection), the control set and the factory.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "handshare/controls/controls.hpp"

namespace handshare::controls {

namespace {

// A hand leaves the approach zone only this far outside it, so that a fingertip hovering at
// the border does not count a miss per crossing.
constexpr double kExitHysteresis_m = 0.005;

bool Finite(const Eigen::Vector3d& p) noexcept { return p.allFinite(); }

}  // namespace

const char* ToString(EventKind kind) noexcept {
  switch (kind) {
    case EventKind::kPressed: return "PRESSED";
    case EventKind::kReleased: return "RELEASED";
    case EventKind::kMoved: return "MOVED";
    case EventKind::kPageTurned: return "PAGE_TURNED";
    case EventKind::kMissed: return "MISSED";
    case EventKind::kOpened: return "OPENED";
    case EventKind::kMoving: return "MOVING";
  }
  return "?";
}

Control::Control(const scene::ControlSpec& spec) : spec_(spec) {
  Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();
  X_WC.linear() = spec.q_WC.normalized().toRotationMatrix();
  X_WC.translation() = spec.p_WC_m;
  X_CW_ = X_WC.inverse();
  R_WC_ = X_WC.linear();
  switch (spec.type) {
    case scene::ControlType::kButton:
    case scene::ControlType::kArrow: motion_resolution_ = spec.push.travel_m / 20.0; break;
    case scene::ControlType::kLever: motion_resolution_ = 0.01; break;
    case scene::ControlType::kBook: motion_resolution_ = 0.05; break;
  }
}

void Control::SyncMotion() noexcept {
  last_position_ = reported_position_ = position();
  since_report_s_ = 0.0;
  reporting_ = false;
}

void Control::ReportMotion(double dt_s, EventBuffer& events) noexcept {
  const double now = position();
  since_report_s_ += dt_s;
  const bool still = std::abs(now - last_position_) <= 1e-12;
  last_position_ = now;
  const auto report = [&](bool moving) {
    Emit(events, EventKind::kMoving, -1, now, 0.0, moving ? 1 : 0);
    reported_position_ = now;
    since_report_s_ = 0.0;
    reporting_ = moving;
  };
  if (touched() || !still) {
    if (std::abs(now - reported_position_) > motion_resolution_ && since_report_s_ >= kMotionPeriod_s) report(true);
  } else if (reporting_ || std::abs(now - reported_position_) > motion_resolution_) {
    report(false);  // left alone and still: where it rests
  }
}

void Control::Step(double dt_s, std::span<const Eigen::Vector3d> p_WE, double fingertip_radius_m,
                   std::span<Eigen::Vector3d> f_E_W, EventBuffer& events) noexcept {
  if (requested_.waiting && !touched()) {
    ApplyState(requested_.index, requested_.engaged);
    requested_.waiting = false;
    SyncMotion();  // moved from elsewhere: not this hand's motion to report
  }
  if (first_step_) SyncMotion();
  const std::size_t n = std::min({p_WE.size(), f_E_W.size(), static_cast<std::size_t>(kMaxFingertips)});
  for (std::size_t i = 0; i < n; ++i) {
    present_[i] = Finite(p_WE[i]);
    p_CE_[i] = present_[i] ? Eigen::Vector3d(X_CW_ * p_WE[i]) : Eigen::Vector3d::Zero();
    f_E_C_[i].setZero();
  }
  const Fingers fingers{std::span<const Eigen::Vector3d>(p_CE_.data(), n),
                        std::span<const bool>(present_.data(), n), fingertip_radius_m};
  if (dt_s > 0.0 && std::isfinite(dt_s) && std::isfinite(fingertip_radius_m) && fingertip_radius_m >= 0.0) {
    StepModel(dt_s, fingers, std::span<Eigen::Vector3d>(f_E_C_.data(), n), events);
  }
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Vector3d f = f_E_C_[i];
    if (!f.allFinite()) f.setZero();  // a model bug must not reach the device
    const double norm = f.norm();
    if (norm > spec_.max_force_N) f *= spec_.max_force_N / norm;
    f_E_W[i].noalias() += R_WC_ * f;
  }
  TrackApproach(fingers, events);
  if (dt_s > 0.0 && std::isfinite(dt_s)) ReportMotion(dt_s, events);
  first_step_ = false;
}

void Control::Emit(EventBuffer& events, EventKind kind, int tip, double value, double error_m,
                   int index) noexcept {
  // A hand that was on the control when it appeared (its visit began at the first step) does
  // not actuate it until it has left: the arrow of the next world, at the place of the arrow
  // just pressed, must not be pressed by the same push.
  const int hand = tip >= 0 ? tip / kFingers : -1;
  if (guard_first_visits_ && hand >= 0 && hand < kMaxHands) {
    const Visit& v = visits_[static_cast<std::size_t>(hand)];
    if (first_step_ || (v.inside && !v.counts)) return;  // (the visit begins after the first model step)
  }
  ControlEvent e;
  const std::size_t len = std::min(spec_.id.size(), e.control_id.size() - 1);
  std::memcpy(e.control_id.data(), spec_.id.data(), len);
  e.control_id[len] = '\0';
  e.type = spec_.type;
  e.kind = kind;
  e.index = index;
  e.value = value;
  e.error_m = error_m;
  e.hand = tip >= 0 ? tip / kFingers : -1;
  e.finger = tip >= 0 ? tip % kFingers : -1;
  events.Push(e);
  const bool actuation = kind == EventKind::kPressed || kind == EventKind::kMoved ||
                         kind == EventKind::kOpened || kind == EventKind::kPageTurned;
  if (actuation && e.hand >= 0 && e.hand < kMaxHands) visits_[static_cast<std::size_t>(e.hand)].actuated = true;
}

// Miss detection, per hand: a visit starts when any fingertip of the hand comes within
// approach_margin_m of the control's box, and ends when all of them are farther than that
// (plus hysteresis). A visit that ends without an actuation by that hand is one miss.
bool Control::touched() const noexcept {
  for (const Visit& v : visits_) {
    if (v.inside) return true;
  }
  return false;
}

void Control::TrackApproach(const Fingers& fingers, EventBuffer& events) noexcept {
  const Eigen::AlignedBox3d box = Bounds_C();
  const Eigen::Vector3d target = Target_C();
  const int hands = std::min(static_cast<int>(fingers.p_CE.size()) / kFingers, kMaxHands);
  for (int h = 0; h < hands; ++h) {
    Visit& v = visits_[static_cast<std::size_t>(h)];
    double nearest_box = std::numeric_limits<double>::infinity();
    double nearest_target = std::numeric_limits<double>::infinity();
    int nearest_tip = -1;
    for (int k = 0; k < kFingers; ++k) {
      const int tip = h * kFingers + k;
      if (!fingers.present[static_cast<std::size_t>(tip)]) continue;
      const Eigen::Vector3d& p = fingers.p_CE[static_cast<std::size_t>(tip)];
      nearest_box = std::min(nearest_box, std::sqrt(box.squaredExteriorDistance(p)));
      const double d = (p - target).norm();
      if (d < nearest_target) {
        nearest_target = d;
        nearest_tip = tip;
      }
    }
    if (!v.inside) {
      if (nearest_box <= spec_.approach_margin_m) {
        v = Visit{.inside = true, .actuated = false, .counts = !first_step_,
                  .closest_m = nearest_target, .closest_tip = nearest_tip};
      }
      continue;
    }
    if (nearest_target < v.closest_m) {
      v.closest_m = nearest_target;
      v.closest_tip = nearest_tip;
    }
    if (nearest_box > spec_.approach_margin_m + kExitHysteresis_m) {
      v.inside = false;
      if (!v.actuated && v.counts) {
        ++missed_count_;
        Emit(events, EventKind::kMissed, v.closest_tip, v.closest_m, v.closest_m);
      }
    }
  }
}

const scene::Action* ActionOf(const scene::ControlSpec& spec, EventKind kind, std::int32_t index) noexcept {
  const auto pick = [](const std::vector<scene::Action>& list, std::int32_t i) -> const scene::Action* {
    return i >= 0 && static_cast<std::size_t>(i) < list.size() ? &list[static_cast<std::size_t>(i)] : nullptr;
  };
  const bool clickable = spec.type == scene::ControlType::kButton || spec.type == scene::ControlType::kArrow;
  const bool book = spec.type == scene::ControlType::kBook;
  const scene::Action* a = nullptr;
  switch (kind) {
    case EventKind::kPressed: a = clickable ? &spec.action : nullptr; break;
    case EventKind::kOpened:
      if (book) a = spec.action.empty() ? pick(spec.page_actions, 0) : &spec.action;
      break;
    case EventKind::kMoved: a = spec.type == scene::ControlType::kLever ? pick(spec.detent_actions, index) : nullptr; break;
    case EventKind::kPageTurned: a = book ? pick(spec.page_actions, index) : nullptr; break;
    case EventKind::kReleased:
    case EventKind::kMissed:
    case EventKind::kMoving: break;
  }
  return a != nullptr && !a->empty() ? a : nullptr;
}

const scene::Action* Control::ActionFor(const ControlEvent& e) const noexcept { return ActionOf(spec_, e.kind, e.index); }

ControlSet::ControlSet(std::vector<std::unique_ptr<Control>> controls) : controls_(std::move(controls)) {
  for (const auto& c : controls_) max_force_N_ = std::max(max_force_N_, c->spec().max_force_N);
}

void ControlSet::Step(double dt_s, std::span<const Eigen::Vector3d> p_WE, double fingertip_radius_m,
                      std::span<Eigen::Vector3d> f_E_W, EventBuffer& events) noexcept {
  for (auto& f : f_E_W) f.setZero();
  for (auto& c : controls_) c->Step(dt_s, p_WE, fingertip_radius_m, f_E_W, events);
  // Two controls touched by one finger must not add up beyond the finger's limit.
  for (auto& f : f_E_W) {
    const double norm = f.norm();
    if (norm > max_force_N_) f *= max_force_N_ / norm;
  }
}

void ControlSet::SetGuardFirstVisits(bool on) noexcept {
  for (auto& c : controls_) c->SetGuardFirstVisits(on);
}

Control* ControlSet::Find(std::string_view id) noexcept {
  for (auto& c : controls_) {
    if (c->id() == id) return c.get();
  }
  return nullptr;
}

const scene::Action* ControlSet::ActionFor(const ControlEvent& e) const noexcept {
  for (const auto& c : controls_) {
    if (c->id() == e.id()) return c->ActionFor(e);
  }
  return nullptr;
}

std::unique_ptr<Control> MakeControl(const scene::ControlSpec& spec) {
  switch (spec.type) {
    case scene::ControlType::kButton:
    case scene::ControlType::kArrow: return std::make_unique<PushControl>(spec);
    case scene::ControlType::kLever: return std::make_unique<Lever>(spec);
    case scene::ControlType::kBook: return std::make_unique<Book>(spec);
  }
  return nullptr;
}

ControlSet MakeControls(const scene::Scene& scene) {
  std::vector<std::unique_ptr<Control>> controls;
  for (const auto& spec : scene.controls) controls.push_back(MakeControl(spec));
  return ControlSet(std::move(controls));
}

}  // namespace handshare::controls
