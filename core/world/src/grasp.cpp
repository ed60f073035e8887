#include "handshare/world/grasp.hpp"

#include <cmath>

namespace handshare::world {

bool IsGrasp(const FingerForce* fingers, std::size_t count, double min_force_N, double min_angle_rad) {
  const double cos_limit = std::cos(min_angle_rad);
  auto norm = [](const FingerForce& f) {
    return std::sqrt(f.f_W_N[0] * f.f_W_N[0] + f.f_W_N[1] * f.f_W_N[1] + f.f_W_N[2] * f.f_W_N[2]);
  };
  for (std::size_t i = 0; i < count; ++i) {
    const double ni = norm(fingers[i]);
    if (!fingers[i].active || !(ni >= min_force_N)) continue;  // also rejects NaN
    for (std::size_t j = i + 1; j < count; ++j) {
      const double nj = norm(fingers[j]);
      if (!fingers[j].active || !(nj >= min_force_N)) continue;
      const double dot = fingers[i].f_W_N[0] * fingers[j].f_W_N[0] + fingers[i].f_W_N[1] * fingers[j].f_W_N[1] +
                         fingers[i].f_W_N[2] * fingers[j].f_W_N[2];
      // The angle between the two forces is at least min_angle: cos(angle) <= cos(min_angle).
      if (dot <= cos_limit * ni * nj) return true;
    }
  }
  return false;
}

}  // namespace handshare::world
