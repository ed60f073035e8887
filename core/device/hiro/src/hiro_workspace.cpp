#include "handshare/hiro/hiro_workspace.hpp"

#include <cmath>
#include <limits>

namespace handshare::hiro {

FingerVector MirrorFingerPosture(const FingerSpec& finger, const FingerVector& q) noexcept {
  const double l2 = finger.link_m[1], l3 = finger.link_m[2];
  return FingerVector(q[0], q[1] + 2.0 * std::atan2(l3 * std::sin(q[2]), l2 + l3 * std::cos(q[2])), -q[2]);
}

double FingerWorkspaceVolume(const FingerSpec& finger, int n_q1, int n_q23) noexcept {
  const JointSpec &j1 = finger.joint[0], &j2 = finger.joint[1], &j3 = finger.joint[2];
  if (j1.max_rad - j1.min_rad >= M_PI || j2.max_rad - j2.min_rad >= 2.0 * M_PI || j3.min_rad < -M_PI ||
      j3.max_rad > M_PI || n_q1 < 1 || n_q23 < 1) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  const double h1 = (j1.max_rad - j1.min_rad) / n_q1, h2 = (j2.max_rad - j2.min_rad) / n_q23,
               h3 = (j3.max_rad - j3.min_rad) / n_q23;
  auto in_range = [](const JointSpec& j, double q) { return q >= j.min_rad && q <= j.max_rad; };
  double sum = 0.0;
  for (int a = 0; a < n_q1; ++a) {
    for (int b = 0; b < n_q23; ++b) {
      for (int c = 0; c < n_q23; ++c) {
        const FingerVector q(j1.min_rad + (a + 0.5) * h1, j2.min_rad + (b + 0.5) * h2, j3.min_rad + (c + 0.5) * h3);
        const double det = std::abs(FingerFk(finger, q).J_HE.determinant());
        const FingerVector m = MirrorFingerPosture(finger, q);
        const int postures = in_range(j2, m[1]) && in_range(j3, m[2]) ? 2 : 1;
        sum += det / postures;
      }
    }
  }
  return sum * h1 * h2 * h3;
}

}  // namespace handshare::hiro
