#include "handshare/graphics/desk_feedback.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>

namespace handshare::graphics {

render::Rgb ForceColour(double force_N, double max_force_N) {
  const double t = max_force_N > 0.0 ? std::clamp(force_N / max_force_N, 0.0, 1.0) : 0.0;
  // White -> yellow over the first half, yellow -> red over the second.
  if (t < 0.5) {
    const auto b = static_cast<float>(1.0 - 2.0 * t);
    return render::Rgb{1.0F, 1.0F, b};
  }
  return render::Rgb{1.0F, static_cast<float>(2.0 - 2.0 * t), 0.0F};
}

void AddForceFeedback(const std::array<Eigen::Vector3d, common::kFingers>& p_WE,
                      const std::array<Eigen::Vector3d, common::kFingers>& f_E_W_N, double fingertip_radius_m,
                      double max_force_N, render::SceneView& view) {
  constexpr double kMinForce_N = 0.02;
  for (int i = 0; i < common::kFingers; ++i) {
    const double f = f_E_W_N[i].norm();
    const render::Rgb rgb = ForceColour(f, max_force_N);
    view.markers.push_back(render::Sphere{p_WE[i], fingertip_radius_m, rgb});
    if (!(f > kMinForce_N) || !p_WE[i].allFinite()) continue;
    const Eigen::Vector3d dir = f_E_W_N[i] / f;
    const double length_m = kForceArrow_m_per_N * f;
    render::Box shaft;
    shaft.p_W = p_WE[i] + 0.5 * length_m * dir;
    shaft.half_extents_m = Eigen::Vector3d(0.0012, 0.5 * length_m, 0.0012);
    shaft.q_WB = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitY(), dir);
    shaft.rgb = rgb;
    view.hand_boxes.push_back(shaft);
    view.markers.push_back(render::Sphere{p_WE[i] + length_m * dir, 0.0025, rgb});
  }
}

double HeldWeight_N(const std::array<Eigen::Vector3d, common::kFingers>& f_E_W_N) {
  double up_N = 0.0;
  for (const auto& f : f_E_W_N) up_N += f.z();
  return std::max(0.0, -up_N);
}

std::string ForceReadout(const std::array<Eigen::Vector3d, common::kFingers>& f_E_W_N) {
  static constexpr const char* kNames[common::kFingers] = {"thumb", "index", "middle", "ring", "little"};
  std::string out = "forces [N]:";
  char part[48];
  double up_N = 0.0;
  for (int i = 0; i < common::kFingers; ++i) {
    std::snprintf(part, sizeof part, " %s %.2f", kNames[i], f_E_W_N[i].norm());
    out += part;
    up_N += f_E_W_N[i].z();
  }
  if (up_N < -0.02) {
    std::snprintf(part, sizeof part, "\nweight held %.2f N", -up_N);
  } else if (up_N > 0.02) {
    std::snprintf(part, sizeof part, "\npressing down %.2f N", up_N);
  } else {
    std::snprintf(part, sizeof part, "\nno load");
  }
  return out + part;
}

}  // namespace handshare::graphics
