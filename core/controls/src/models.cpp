// Force profiles of the push button / arrow, the lever and the book (see controls.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "handshare/controls/controls.hpp"

namespace handshare::controls {

namespace {
// The preload of a button spring is felt over the first 0.3 mm of travel, not as a step at
// zero depth (a step would chatter at the surface).
constexpr double kPreloadRamp_m = 0.0003;
// Tangential resistance of a dragged cover or page builds up over 5 mm of drag.
constexpr double kDragRamp_m = 0.005;
}  // namespace

// ---------------------------------------------------------------------------------------------
// Push button and arrow

PushControl::PushControl(const scene::ControlSpec& spec) : Control(spec) {}

double PushControl::SpringForce_N(double q_m, bool clicked) const noexcept {
  const auto& p = spec_.push;
  const double q = std::clamp(q_m, 0.0, p.travel_m);
  const double f = p.preload_N * std::min(1.0, q / kPreloadRamp_m) + p.stiffness_N_per_m * q;
  return clicked ? f * (1.0 - p.click_drop) : f;
}

void PushControl::StepModel(double, const Fingers& fingers, std::span<Eigen::Vector3d> f_E_C,
                            EventBuffer& events) noexcept {
  const auto& p = spec_.push;
  const double hx = 0.5 * spec_.size_m.x();
  const double hy = 0.5 * spec_.size_m.y();
  const double r = fingers.radius_m;
  // The massless cap follows the deepest fingertip over the face.
  double depth = 0.0;
  int tip = -1;
  for (std::size_t i = 0; i < fingers.p_CE.size(); ++i) {
    if (!fingers.present[i]) continue;
    const Eigen::Vector3d& e = fingers.p_CE[i];
    if (std::abs(e.x()) > hx || std::abs(e.y()) > hy) continue;
    if (e.z() < -(p.travel_m + 0.5 * r)) continue;  // inside the body: not on the cap
    const double d = r - e.z();
    if (d > depth) {
      depth = d;
      tip = static_cast<int>(i);
    }
  }
  travel_m_ = std::min(depth, p.travel_m);
  if (tip >= 0) last_tip_ = tip;
  const auto lateral = [&](int i) {
    return i >= 0 ? fingers.p_CE[static_cast<std::size_t>(i)].head<2>().norm() : 0.0;
  };
  // State first, so that the force drop happens at the click itself.
  if (!pressed_ && travel_m_ >= p.click_at_m) {
    pressed_ = true;
    Emit(events, EventKind::kPressed, tip, travel_m_, lateral(tip));
  } else if (pressed_ && travel_m_ <= p.release_at_m) {
    pressed_ = false;
    const int who = tip >= 0 ? tip : last_tip_;
    const bool still_there = who >= 0 && fingers.present[static_cast<std::size_t>(who)];
    Emit(events, EventKind::kReleased, who, travel_m_, still_there ? lateral(who) : 0.0);
  }
  if (tip < 0) return;
  const double force = SpringForce_N(travel_m_, pressed_) +
                       p.stop_stiffness_N_per_m * std::max(0.0, depth - p.travel_m);
  f_E_C[static_cast<std::size_t>(tip)] += Eigen::Vector3d(0.0, 0.0, force);
}

Eigen::AlignedBox3d PushControl::Bounds_C() const noexcept {
  const Eigen::Vector3d h(0.5 * spec_.size_m.x(), 0.5 * spec_.size_m.y(), 0.0);
  return Eigen::AlignedBox3d(Eigen::Vector3d(-h.x(), -h.y(), -spec_.size_m.z()), h);
}

// ---------------------------------------------------------------------------------------------
// Lever

Lever::Lever(const scene::ControlSpec& spec) : Control(spec) {
  const auto& l = spec.lever;
  spacing_rad_ = l.spacing_rad();
  angle_rad_ = l.min_angle_rad;
}

void Lever::ApplyState(std::int32_t index, bool /*engaged*/) noexcept {
  const auto& l = spec_.lever;
  if (index < 0 || index >= std::max(1, l.detents)) return;
  angle_rad_ = std::clamp(l.detent_angle_rad(index), l.min_angle_rad, l.max_angle_rad);
  detent_ = index;
}

double Lever::DetentTorque_N_m(double angle_rad) const noexcept {
  const auto& l = spec_.lever;
  if (l.detents < 2 || spacing_rad_ <= 0.0) return 0.0;
  return -l.detent_torque_N_m * std::sin(2.0 * std::numbers::pi * (angle_rad - l.min_angle_rad) / spacing_rad_);
}

void Lever::StepModel(double dt_s, const Fingers& fingers, std::span<Eigen::Vector3d> f_E_C,
                      EventBuffer& events) noexcept {
  const auto& l = spec_.lever;
  const double length = spec_.size_m.z();
  const double half_thick = 0.5 * spec_.size_m.y();
  const double half_wide = 0.5 * spec_.size_m.x();
  const double r = fingers.radius_m;
  const double prev = angle_rad_;

  // Without fingers the handle creeps into the nearest detent (overdamped, rate-limited).
  double angle = prev;
  if (l.detent_torque_N_m > 0.0) {
    angle += dt_s * l.settle_rate_rad_per_s * std::clamp(DetentTorque_N_m(prev) / l.detent_torque_N_m, -1.0, 1.0);
  }

  // Each fingertip near the handle is a one-sided limit on the angle: a fingertip at polar
  // angle phi (about x, same convention as the handle) and distance rho from the hinge touches
  // the handle when |angle - phi| = asin((thickness/2 + r) / rho).
  struct Limit {
    int side = 0;  // +1: on the +y side (pushes the angle up), -1: -y side, 0: not near
    double bound = 0.0;
    double rho = 0.0;
  };
  std::array<Limit, kMaxFingertips> limits{};
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < fingers.p_CE.size(); ++i) {
    if (!fingers.present[i]) continue;
    const Eigen::Vector3d& e = fingers.p_CE[i];
    if (std::abs(e.x()) > half_wide + r) continue;
    const double rho = std::hypot(e.y(), e.z());
    if (rho <= half_thick + r) continue;  // at the hinge: nothing to push
    const double phi = std::atan2(-e.y(), e.z());
    const double along = rho * std::cos(phi - prev);
    if (along < 0.0 || along > length) continue;  // beyond the ends of the handle
    const double alpha = std::asin((half_thick + r) / rho);
    Limit& lim = limits[i];
    lim.rho = rho;
    if (phi < prev) {
      lim.side = +1;
      lim.bound = phi + alpha;
      lower = std::max(lower, lim.bound);
    } else {
      lim.side = -1;
      lim.bound = phi - alpha;
      upper = std::min(upper, lim.bound);
    }
  }
  angle = lower > upper ? 0.5 * (lower + upper) : std::clamp(angle, lower, upper);
  angle = std::clamp(angle, l.min_angle_rad, l.max_angle_rad);
  angle_rad_ = angle;

  // Forces: the fingertips in contact hold the detent torque (shared), and press into the
  // stop stiffness where the handle cannot follow (end stops, pinching).
  const double hold_N_m = -DetentTorque_N_m(angle);  // > 0: must be pushed from the +y side
  int n_plus = 0, n_minus = 0;
  constexpr double kTouching_rad = 1e-9;
  for (const Limit& lim : limits) {
    if (lim.side > 0 && lim.bound >= angle - kTouching_rad) ++n_plus;
    if (lim.side < 0 && lim.bound <= angle + kTouching_rad) ++n_minus;
  }
  const Eigen::Vector3d normal(0.0, std::cos(angle), std::sin(angle));  // out of the +y face
  double strongest = 0.0;
  for (std::size_t i = 0; i < fingers.p_CE.size(); ++i) {
    const Limit& lim = limits[i];
    double force = 0.0;
    if (lim.side > 0 && lim.bound >= angle - kTouching_rad) {
      const double pen = lim.rho * std::sin(std::max(0.0, lim.bound - angle));
      force = std::max(0.0, hold_N_m) / lim.rho / n_plus + l.stop_stiffness_N_per_m * pen;
      f_E_C[i] += force * normal;
    } else if (lim.side < 0 && lim.bound <= angle + kTouching_rad) {
      const double pen = lim.rho * std::sin(std::max(0.0, angle - lim.bound));
      force = std::max(0.0, -hold_N_m) / lim.rho / n_minus + l.stop_stiffness_N_per_m * pen;
      f_E_C[i] -= force * normal;
    } else {
      continue;
    }
    if (force >= strongest) {
      strongest = force;
      last_pusher_ = static_cast<int>(i);
    }
  }

  // A detent other than the last reported one, reached (within a tenth of the spacing).
  const int k = static_cast<int>(std::lround((angle - l.min_angle_rad) / spacing_rad_));
  const double at = l.min_angle_rad + k * spacing_rad_;
  if (k != detent_ && std::abs(angle - at) < 0.1 * spacing_rad_) {
    detent_ = k;
    const bool known = last_pusher_ >= 0 && static_cast<std::size_t>(last_pusher_) < fingers.p_CE.size() &&
                       fingers.present[static_cast<std::size_t>(last_pusher_)];
    const double error = known ? (fingers.p_CE[static_cast<std::size_t>(last_pusher_)] - Target_C()).norm() : 0.0;
    Emit(events, EventKind::kMoved, last_pusher_, at, error, k);
  }
}

Eigen::AlignedBox3d Lever::Bounds_C() const noexcept {
  const auto& l = spec_.lever;
  const double length = spec_.size_m.z();
  Eigen::AlignedBox3d box(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  for (double a : {l.min_angle_rad, l.max_angle_rad, std::clamp(0.0, l.min_angle_rad, l.max_angle_rad)}) {
    box.extend(Eigen::Vector3d(0.0, -length * std::sin(a), length * std::cos(a)));
  }
  const Eigen::Vector3d pad(0.5 * spec_.size_m.x(), 0.5 * spec_.size_m.y(), 0.5 * spec_.size_m.y());
  return Eigen::AlignedBox3d(box.min() - pad, box.max() + pad);
}

Eigen::Vector3d Lever::Target_C() const noexcept {
  const double length = spec_.size_m.z();
  return Eigen::Vector3d(0.0, -length * std::sin(angle_rad_), length * std::cos(angle_rad_));
}

// ---------------------------------------------------------------------------------------------
// Book

Book::Book(const scene::ControlSpec& spec) : Control(spec) {}

void Book::ApplyState(std::int32_t index, bool engaged) noexcept {
  open_ = engaged;
  page_ = engaged ? std::max(0, index) : 0;
  cover_angle_rad_ = engaged ? std::numbers::pi : 0.0;
}

void Book::StepModel(double, const Fingers& fingers, std::span<Eigen::Vector3d> f_E_C,
                     EventBuffer& events) noexcept {
  const auto& b = spec_.book;
  const double width = spec_.size_m.x();
  const double half_h = 0.5 * spec_.size_m.y();
  const double thick = spec_.size_m.z();
  const double r = fingers.radius_m;
  const double left_edge = open_ ? -1.5 * width : -0.5 * width;
  double cover = open_ ? std::numbers::pi : 0.0;

  for (std::size_t i = 0; i < fingers.p_CE.size(); ++i) {
    Touch& t = touches_[i];
    const Eigen::Vector3d& e = fingers.p_CE[i];
    const bool over = fingers.present[i] && e.x() >= left_edge && e.x() <= 0.5 * width &&
                      std::abs(e.y()) <= half_h && e.z() > -thick;
    const double depth = r - e.z();
    if (!over || depth <= 0.0) {
      t = Touch{};  // lifted: the next touch may turn again
      continue;
    }
    if (!t.active) t = Touch{.active = true, .used = false, .start_xy = e.head<2>()};
    const double dx = e.x() - t.start_xy.x();
    double drag_N = 0.0;
    if (!t.used && !open_ && dx < 0.0) {
      // The finger carries the cover towards the spine.
      const double angle = std::numbers::pi * std::min(1.0, -dx / width);
      cover = std::max(cover, angle);
      drag_N = b.page_drag_N * std::min(1.0, -dx / kDragRamp_m);
      if (angle >= b.open_angle_rad) {
        open_ = true;
        page_ = 0;
        cover = std::numbers::pi;
        t.used = true;
        const double error = (t.start_xy - Eigen::Vector2d(0.5 * width, 0.0)).norm();
        Emit(events, EventKind::kOpened, static_cast<int>(i), 0.0, error, 0);
      }
    } else if (!t.used && open_) {
      const bool on_right = t.start_xy.x() >= -0.5 * width;
      const double drag = on_right ? -dx : dx;  // towards the spine on the right, away on the left
      if (drag > 0.0) {
        drag_N = (on_right ? 1.0 : -1.0) * b.page_drag_N * std::min(1.0, drag / kDragRamp_m);
        if (drag >= b.swipe_m) {
          t.used = true;
          const int next = page_ + (on_right ? 1 : -1);
          if (next >= 0 && next < b.pages) {
            page_ = next;
            const Eigen::Vector2d centre(on_right ? 0.0 : -width, 0.0);
            Emit(events, EventKind::kPageTurned, static_cast<int>(i), page_,
                 (t.start_xy - centre).norm(), page_);
          }
        }
      }
    }
    f_E_C[i] += Eigen::Vector3d(drag_N, 0.0, b.surface_stiffness_N_per_m * depth);
  }
  cover_angle_rad_ = cover;  // a half-lifted cover without its finger falls shut
}

Eigen::AlignedBox3d Book::Bounds_C() const noexcept {
  const double w = spec_.size_m.x();
  const double h = 0.5 * spec_.size_m.y();
  return Eigen::AlignedBox3d(Eigen::Vector3d(open_ ? -1.5 * w : -0.5 * w, -h, -spec_.size_m.z()),
                             Eigen::Vector3d(0.5 * w, h, 0.0));
}

Eigen::Vector3d Book::Target_C() const noexcept {
  return open_ ? Eigen::Vector3d::Zero() : Eigen::Vector3d(0.5 * spec_.size_m.x(), 0.0, 0.0);
}

}  // namespace handshare::controls
