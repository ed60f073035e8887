#pragma once
// Shared helpers of the contact tests.
#include <array>
#include <memory>

#include <Eigen/Core>

#include "handshare/contact/haptic_world.hpp"
#include "handshare/fem/compliance.hpp"
#include "handshare/fem/mesh.hpp"

namespace handshare::contact::test {

/// Five fingertips at the same point (the other fingers parked far away when `park`).
inline std::array<Eigen::Vector3d, kFingers> OneFinger(const Eigen::Vector3d& p, bool park = true) {
  std::array<Eigen::Vector3d, kFingers> a;
  for (int i = 0; i < kFingers; ++i) a[static_cast<std::size_t>(i)] = park ? Eigen::Vector3d(10.0 + i, 10.0, 10.0) : p;
  a[0] = p;
  return a;
}

/// A 6 x 6 x 3 cm block of 4 mm cells, bottom fixed, E = 20 kPa (soft tissue-like), and its
/// compliance: the deformable of the contact tests (top face at z = 3 cm in its frame).
struct SoftBlock {
  std::shared_ptr<fem::TetMesh> mesh;
  std::shared_ptr<const fem::Compliance> C;
};

inline SoftBlock MakeSoftBlock() {
  SoftBlock s;
  s.mesh = std::make_shared<fem::TetMesh>(fem::MakeBoxMesh({0.06, 0.06, 0.03}, {15, 15, 6}));
  const auto fixed = fem::NodesOnPlane(*s.mesh, 2, 0.0);
  s.C = std::make_shared<const fem::Compliance>(fem::Compliance::Precompute(*s.mesh, fem::Material{2e4, 0.3}, fixed));
  return s;
}

}  // namespace handshare::contact::test
