#pragma once
/// Perceptual deadband coding of a hand's contact set, the peer stream every other process that
/// shares a world reads (the other haptic nodes, the world server, recorders).
///
/// The sender's bridge offers its newest set every tick; a set goes out only when it differs
/// perceptibly from the last one sent (Weber's law: a change of a force or an imposed
/// displacement smaller than `weber` times its magnitude is not felt; Hinterseer, Hirche,
/// Chaudhuri, Steinbach and Buss, "Perception-based data reduction and transmission of haptic
/// data in telepresence and teleaction systems", IEEE Trans. Signal Processing 56(2), 2008), or
/// when `keepalive` has passed since the last one (so a receiver tells a still hand from a gone
/// one: contact::PeerFade starts its fade well after two keepalives). The receiver reconstructs
/// the stream by holding the newest set (zero-order hold, session::PeerContacts): the passive
/// choice, since an extrapolating receiver can push energy into a stiff contact.
///
/// Anything that changes what the receiver solves at once always goes out: a finger touching or
/// lifting, another object or surface node, a new grasp or owner claim (a let-go with the
/// body's velocity), the last set with no finger on.
///
/// Only what a receiver reads counts: on a deformable, each finger's contact point, imposed
/// displacement and force (contact::PeerContact; the fingertip centre, normal and depth ride
/// along); on a rigid body or a control only that the finger is there; the claims; the pose and
/// velocity of a body the hand simulates, which receivers reckon forward at its velocity (a
/// first-order hold: ReckonedPosition), so the sender compares with that reckoning.
/// Quantities without a meaningful magnitude (positions, orientations) use absolute thresholds;
/// forces and displacements use the Weber fraction with an absolute floor (below the floor a
/// change is not felt whatever the magnitude, and a hand near zero force would otherwise send
/// every tick). Not real-time: the bridge thread.
#include <array>
#include <chrono>
#include <cstdint>

#include "handshare/dds/messages.hpp"

namespace handshare::session {

struct DeadbandConfig {
  double weber = 0.10;                   ///< relative change that counts; 0: every set goes out
  double force_floor_N = 0.02;           ///< force changes below this never count
  double displacement_floor_m = 10e-6;   ///< imposed-displacement and depth changes below this never count
  double position_m = 0.5e-3;            ///< contact point and held body moves that count
  double angle_rad = 0.01;               ///< held body turns that count
  std::chrono::nanoseconds keepalive = std::chrono::milliseconds(100);  ///< at least this often
};

/// Why a set goes out (or kNone: it stays home).
enum class DeadbandReason : int {
  kNone = 0,
  kOff,           ///< the deadband is off (weber 0)
  kFirst,         ///< nothing sent yet (or after Reset)
  kStructure,     ///< a finger on or off, another object or node, a grasp, an owner claim
  kForce,         ///< a finger's force moved past its deadband
  kDisplacement,  ///< a finger's imposed displacement or depth moved past its deadband
  kPosition,      ///< a contact point on a deformable moved past its threshold
  kBody,          ///< the simulated body left the receivers' reckoning or turned past its threshold
  kKeepalive,     ///< nothing perceptible changed, but keepalive has passed
};
inline constexpr int kDeadbandReasons = static_cast<int>(DeadbandReason::kKeepalive) + 1;
const char* ToString(DeadbandReason reason) noexcept;

/// The longest a receiver reckons a held body forward from its newest set [s] (two keepalives:
/// one may be lost); after that it holds the body where the reckoning stopped.
inline constexpr double kMaxReckoning_s = 0.2;

/// Where a receiver puts the body a set simulates, age_s after the set was sent: its position
/// moved on at its velocity for at most kMaxReckoning_s.
std::array<double, 3> ReckonedPosition(const msg::ContactSet& set, double age_s);

/// The first perceptible difference of `now` from `sent` (the last set that went out, age_s
/// before), in the order of the enum; kNone when the receiver would not feel the difference.
/// Ignores the header (user, session, stamp, seq). Pure: no clock.
DeadbandReason PerceptibleChange(const msg::ContactSet& sent, const msg::ContactSet& now, double age_s,
                                 const DeadbandConfig& config);

/// The sender's side: remembers the last set sent and counts what it let through.
class ContactSetDeadband {
 public:
  explicit ContactSetDeadband(DeadbandConfig config = {});

  /// The bridge's newest set at now_ns (steady clock): true if it must go out, and then it is
  /// the new reference. reason(), if given, receives why.
  bool Offer(const msg::ContactSet& set, std::uint64_t now_ns, DeadbandReason* reason = nullptr);
  /// Forget the reference (a new scene): the next set goes out.
  void Reset() { have_sent_ = false; }

  const DeadbandConfig& config() const noexcept { return config_; }
  std::uint64_t offered() const noexcept { return offered_; }
  std::uint64_t sent() const noexcept { return sent_; }
  std::uint64_t sent_for(DeadbandReason reason) const noexcept { return by_reason_[static_cast<int>(reason)]; }
  /// Share of offered sets that stayed home, 0..1.
  double reduction() const noexcept {
    return offered_ == 0 ? 0.0 : 1.0 - static_cast<double>(sent_) / static_cast<double>(offered_);
  }

 private:
  DeadbandConfig config_;
  msg::ContactSet last_;
  std::uint64_t last_ns_ = 0;
  bool have_sent_ = false;
  std::uint64_t offered_ = 0;
  std::uint64_t sent_ = 0;
  std::array<std::uint64_t, kDeadbandReasons> by_reason_{};
};

}  // namespace handshare::session
