#pragma once
/// One interface for every haptic device (HIRO II, simulated hands, replay): fingertip poses
/// in, fingertip forces out. Layer 2 (device, docs/ARCHITECTURE.md): no middleware, no
/// rendering. Read() and Command() are called from the haptic thread and must be real-time safe
/// (no allocation, locks, I/O).
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string_view>

#include "handshare/common/hand.hpp"

namespace handshare::haptic {

using common::kFingers;  // thumb, index, middle, ring, little (handshare/common/hand.hpp)

/// A set of fingers: bit f is finger f (thumb bit 0). A device with fewer contact points than a
/// hand (a stylus: one, a gripper: two) has only those fingers; the others are not simulated.
using FingerMask = std::uint8_t;
inline constexpr FingerMask kEveryFinger = static_cast<FingerMask>((1u << kFingers) - 1u);
inline constexpr bool HasFinger(FingerMask mask, int finger) noexcept { return (mask >> finger) & 1u; }

/// What a device reports each haptic step. Positions in world W [m].
struct DeviceReading {
  std::uint64_t stamp_ns = 0;                  // steady clock at sampling
  Eigen::Vector3d p_WH = Eigen::Vector3d::Zero();            // hand base H
  Eigen::Vector4d q_WH_wxyz = Eigen::Vector4d(1, 0, 0, 0);  // hand base orientation
  std::array<Eigen::Vector3d, kFingers> p_WE{};              // fingertips E (those in finger_mask)
  FingerMask finger_mask = kEveryFinger;                     // the fingers the device has
  std::array<double, common::kHandJoints> q_hand_rad{};  // finger f, joint j at 3 f + j
  std::array<double, common::kArmJoints> q_arm_rad{};
  bool valid = false;                          // false: device lost or data not trustworthy
};

struct DeviceCapabilities {
  int fingers = kFingers;               // contact points, 1 to kFingers
  FingerMask finger_mask = kEveryFinger;  // which fingers they are
  double workspace_radius_m = 0.2;      // the fingertips reach a sphere this big [m]
  bool has_gripper = false;
  double max_fingertip_force_N = 3.5;  // HIRO II: about 3.5 N at the fingertip
  double fingertip_radius_m = 0.008;
  /// Bound on how fast a fingertip force may change [N/s] (the safety stage's rate bound).
  double max_force_rate_N_per_s = 2000.0;
  /// Native control rate of the device [Hz] (HIRO II: 1 kHz).
  double control_rate_Hz = 1000.0;
  int hand_joints = 0;  // actuated joints in the hand (HIRO II: common::kHandJoints); 0 for scripted hands
  int arm_joints = 0;   // actuated joints in the arm (HIRO II: common::kArmJoints)
};

class Device {
 public:
  virtual ~Device() = default;
  virtual DeviceCapabilities capabilities() const noexcept = 0;
  /// Samples the device at time t_s since the loop started. Real-time safe.
  virtual void Read(double t_s, DeviceReading& out) noexcept = 0;
  /// Commands fingertip forces f_E_W [N] (already clamped by the caller). Real-time safe.
  virtual void Command(const std::array<Eigen::Vector3d, kFingers>& f_E_W) noexcept = 0;
  /// Short name: "sim", "hiro", "replay", "desk", "plugin:<name>".
  virtual const char* name() const noexcept = 0;
  /// The node has the world `world` (its scene name) from t_s on the Read clock: called after
  /// every scene change, from the bridge thread, while Read runs on the haptic thread (no
  /// allocation, no locks). A scripted hand holding at an await_world for it runs on; the
  /// return is true the one time this starts a script that holds at its very start. Devices
  /// without a script ignore it.
  virtual bool OnWorldReady(double /*t_s*/, std::string_view /*world*/) noexcept { return false; }
};

}  // namespace handshare::haptic
