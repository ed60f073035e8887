#include "desk_device.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "handshare/common/clock.hpp"

namespace handshare::haptic {

namespace {

// The farthest fingertip from the hand base (the ring open: |centre| + its radius, 0.076 +
// 0.075 m), and the path a fingertip takes from open to closed (the ring's radius change).
constexpr double kFingertipReach_m = 0.16;
constexpr double kClosingPath_m = kDeskRingOpen_m - kDeskRingClosed_m;

// The rotation vector (axis times angle, angle in [0, pi]) of a unit quaternion.
Eigen::Vector3d RotationVector(const std::array<double, 4>& q_wxyz) noexcept {
  Eigen::Quaterniond q(q_wxyz[0], q_wxyz[1], q_wxyz[2], q_wxyz[3]);
  const double n = q.norm();
  if (!(n > 1e-9) || !std::isfinite(n)) return Eigen::Vector3d::Zero();
  q.coeffs() /= n;
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // the shorter way round
  const Eigen::AngleAxisd aa(q);
  return aa.angle() * aa.axis();
}

Eigen::Matrix3d RotationOf(const Eigen::Vector3d& rotation_vector) noexcept {
  const double angle = rotation_vector.norm();
  if (angle < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, rotation_vector / angle).toRotationMatrix();
}

// Scales v down to norm at most max_norm.
template <class V>
void ClampNorm(V& v, double max_norm) noexcept {
  const double n = v.norm();
  if (n > max_norm) v *= max_norm / n;
}

}  // namespace

Eigen::Vector3d DeskFingertip_H(int finger, double closure) noexcept {
  // As the scripted hand's grasp verb: azimuth -90 deg (the thumb, towards the person) + 72 deg
  // a finger, elevation -15 deg.
  constexpr double kPi = 3.14159265358979323846;
  const double azimuth = -0.5 * kPi + 2.0 * kPi * finger / kFingers;
  const double elevation = -15.0 * kPi / 180.0;
  const double c = std::clamp(closure, 0.0, 1.0);
  const double radius = kDeskRingOpen_m + c * (kDeskRingClosed_m - kDeskRingOpen_m);
  const Eigen::Vector3d n(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                          std::sin(elevation));
  return Eigen::Vector3d(0.0, kDeskGraspCentreY_m, kDeskGraspCentreZ_m) + radius * n;
}

double MaxFingertipSpeed(const DeskFilterConfig& c) noexcept {
  return c.max_speed_m_per_s + c.max_turn_rate_rad_per_s * kFingertipReach_m + c.max_closure_rate_per_s * kClosingPath_m;
}

template <int N>
void DeskDevice::Channel<N>::Step(const Eigen::Matrix<double, N, 1>& r, double tau_s, double max_v, double max_a,
                                  double dt_s) noexcept {
  // Critically damped: a = w^2 (r - x) - 2 w v with w = 1 / tau, bounded; semi-implicit Euler.
  const double w = 1.0 / tau_s;
  Eigen::Matrix<double, N, 1> a = w * w * (r - x) - 2.0 * w * v;
  ClampNorm(a, max_a);
  v += a * dt_s;
  ClampNorm(v, max_v);
  x += v * dt_s;
}

DeskDevice::DeskDevice(DeskFilterConfig config) : config_(config) {}

void DeskDevice::Read(double t_s, DeviceReading& out) noexcept {
  if (targets_.Read(target_)) {
    if (!have_target_) {
      // The first target: the hand appears there, at rest (it was not valid before).
      base_.x = Eigen::Vector3d(target_.p_WH_m.data());
      turn_.x = RotationVector(target_.q_WH_wxyz);
      for (int i = 0; i < kFingers; ++i) closure_.x[i] = std::clamp(target_.closure[i], 0.0, 1.0);
      have_target_ = true;
    }
  }
  const double dt_s = last_t_s_ < 0.0 ? 0.0 : std::clamp(t_s - last_t_s_, 0.0, 0.01);
  last_t_s_ = t_s;
  out.stamp_ns = common::SteadyNowNs();  // the loop's staleness check: this sample is new
  const std::uint64_t now_ns = now_ns_ != nullptr ? now_ns_() : out.stamp_ns;
  if (!have_target_) {
    out.valid = false;
    return;
  }

  Eigen::Matrix<double, kFingers, 1> closure_target;
  for (int i = 0; i < kFingers; ++i) closure_target[i] = std::clamp(target_.closure[i], 0.0, 1.0);
  const DeskFilterConfig& c = config_;
  base_.Step(Eigen::Vector3d(target_.p_WH_m.data()), c.tau_s, c.max_speed_m_per_s, c.max_acceleration_m_per_s2, dt_s);
  turn_.Step(RotationVector(target_.q_WH_wxyz), c.tau_s, c.max_turn_rate_rad_per_s,
             c.max_turn_acceleration_rad_per_s2, dt_s);
  closure_.Step(closure_target, c.tau_s, c.max_closure_rate_per_s, c.max_closure_acceleration_per_s2, dt_s);

  // Fingertips: each finger on the grasp ring at its own closure, turned with the hand.
  const Eigen::Matrix3d R_WH = RotationOf(turn_.x);
  const Eigen::Quaterniond q(R_WH);
  out.p_WH = base_.x;
  out.q_WH_wxyz = Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
  for (int i = 0; i < kFingers; ++i) out.p_WE[i] = base_.x + R_WH * DeskFingertip_H(i, closure_.x[i]);

  // Released while the window has no focus or the desk has gone quiet.
  const bool fresh = target_.received_ns != 0 && now_ns >= target_.received_ns &&
                     static_cast<double>(now_ns - target_.received_ns) * 1e-9 <= c.input_timeout_s;
  out.valid = target_.focused && fresh;
}

}  // namespace handshare::haptic
