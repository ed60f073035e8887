#pragma once
/// What the haptic thread hands to the bridge thread each step (trivially copyable).
#include <cstdint>

#include "handshare/haptic/device.hpp"

namespace handshare::haptic {

struct HapticSnapshot {
  std::uint64_t seq = 0;
  std::uint64_t stamp_ns = 0;
  double t_s = 0.0;
  double p_WH_m[3] = {};
  double q_WH_wxyz[4] = {1, 0, 0, 0};
  double p_WE_m[kFingers][3] = {};
  double f_E_W_N[kFingers][3] = {};
  /// Impulse each finger's commanded force has delivered since the loop started: the sum over
  /// every step of f times the time it was held [N s]. Its change over a window divided by the
  /// window's t_s span is the mean force over every step of it (not over the bridge's samples).
  double impulse_E_W_Ns[kFingers][3] = {};
  double fingertip_radius_m = 0.0;
  /// The device's joint angles (zeros for a device without joints): screens draw its hand.
  double q_hand_rad[common::kHandJoints] = {};
  double q_arm_rad[common::kArmJoints] = {};
  bool fault = false;  // device fault or a finger's safety fault this step
  FingerMask finger_mask = kEveryFinger;  // the fingers the device has (p_WE_m of others: the base)
};

}  // namespace handshare::haptic
