#pragma once
/// The hand every layer shares: one finger count, defined once. The DDS layer ties it to the
/// IDL's constant (handshare::msg::kFingers) with a static_assert, so a message and a model
/// can never disagree on how many fingertips a hand has.

namespace handshare::common {

/// Fingertips per hand: thumb, index, middle, ring, little (in this order everywhere).
inline constexpr int kFingers = 5;

}  // namespace handshare::common
