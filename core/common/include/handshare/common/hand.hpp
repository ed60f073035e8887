#pragma once
/// The hand every layer shares: one finger count and one joint count, each defined once. The DDS
/// layer ties them to the IDL's constants (handshare::msg::kFingers, kHandJoints, kArmJoints)
/// with static_asserts, so a message and a model can never disagree on how many fingertips or
/// joint angles a hand has.

namespace handshare::common {

/// Fingertips per hand: thumb, index, middle, ring, little (in this order everywhere).
inline constexpr int kFingers = 5;

/// Joint angles a device reports (DeviceReading, DeviceState): the HIRO II's, 3 per finger (finger
/// f, joint j at 3 f + j) and 6 in the arm. A device with fewer joints leaves the rest zero.
inline constexpr int kFingerJoints = 3;
inline constexpr int kHandJoints = kFingers * kFingerJoints;
inline constexpr int kArmJoints = 6;

}  // namespace handshare::common
