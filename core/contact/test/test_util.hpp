#pragma once
// Shared helpers of the contact tests.
#include <array>

#include <Eigen/Core>

#include "handshare/contact/haptic_world.hpp"

namespace handshare::contact::test {

/// Five fingertips at the same point (the other fingers parked far away when `park`).
inline std::array<Eigen::Vector3d, kFingers> OneFinger(const Eigen::Vector3d& p, bool park = true) {
  std::array<Eigen::Vector3d, kFingers> a;
  for (int i = 0; i < kFingers; ++i) a[static_cast<std::size_t>(i)] = park ? Eigen::Vector3d(10.0 + i, 10.0, 10.0) : p;
  a[0] = p;
  return a;
}

}  // namespace handshare::contact::test
