#pragma once
/// What counts as grasping an object, the same rule in the haptic node that claims an object
/// and in the world server that arbitrates the claims. Plain logic, real-time safe.
#include <cstddef>

namespace handshare::world {

/// Whether one hand's contacts hold an object: at least two fingers on it with forces that
/// push against each other (some pair at least min_angle_rad apart), each at least
/// min_force_N. Forces f_W_N on the object, in world W.
struct FingerForce {
  bool active = false;
  double f_W_N[3] = {0.0, 0.0, 0.0};
};
bool IsGrasp(const FingerForce* fingers, std::size_t count, double min_force_N = 0.05,
             double min_angle_rad = 1.7453292519943295 /* 100 deg */);

}  // namespace handshare::world
