#pragma once
/// How often a haptic node's bridge sends each of its streams: no faster than its readers read
/// them (issue "Many stations on one session", point 2; docs/network.md, "Publish only what is
/// read").
///
/// - Device states are read by graphics nodes only, each at its frame rate (MemberInfo::view_Hz):
///   they go out at the fastest viewer's rate (not below kMinDeviceStateHz, so a slow viewer's
///   stall detection still holds), at the bridge's full rate while any reader has not announced a
///   rate (a recorder, a tool), and not at all without a reader.
/// - Contact sets are read by the world server at its tick (SceneState::tick_Hz: the field
///   viewers see, grasp claims, pushes) and by the other haptic nodes, whose haptic loops put
///   them into their own solves of an object both hands touch. So a set goes at the bridge's
///   full rate while a peer's fresh set touches an object this hand touches, else at the world
///   server's tick rate (full rate when the server has not said). The deadband coding
///   (contact_deadband.hpp) then drops what is not felt.
/// Not real-time: the bridge thread.
#include <cstdint>

#include "handshare/dds/messages.hpp"
#include "handshare/session/peer_contacts.hpp"

namespace handshare::session {

/// A slow viewer's floor: a device-state reader requests a sample every 100 ms (its DEADLINE
/// QoS, deploy/qos: a stream silent that long has stalled), so at least 3 samples a deadline
/// period, or one lost sample would read as a stall.
inline constexpr double kMinDeviceStateHz = 30.0;

/// The device-state rate a bridge ticking at full_Hz should send at: 0 with no reader matched;
/// full_Hz when more readers are matched than graphics nodes announced a rate (some reader
/// has not said how often it reads); else the fastest viewer's rate, within
/// [kMinDeviceStateHz, full_Hz].
double DeviceStateRate(int matched_readers, int viewers, double fastest_view_Hz, double full_Hz);

/// The contact-set rate: full_Hz while a peer shares an object with this hand, else the world
/// server's tick rate (server_tick_Hz; 0 = not said: full_Hz), never above full_Hz.
double ContactSetRate(bool shared, double server_tick_Hz, double full_Hz);

/// Whether a peer's set in `peers`, fresh at `now` (not faded out), has an active finger on an
/// object an active finger of `own` touches, or claims (grasps, simulates) a body `own` touches
/// or claims: then both haptic loops solve that object with the other's contacts.
bool SharesObjectWithPeer(const msg::ContactSet& own, const PeerContacts& peers, PeerContacts::Clock::time_point now);

/// Paces a stream offered on every bridge tick to a rate that may change from tick to tick:
/// Due() says whether this tick may send. The average is the rate; a late tick does not make a
/// burst afterwards.
class StreamPacer {
 public:
  /// tick_Hz: how often Due() is called (the bridge's rate).
  explicit StreamPacer(double tick_Hz);
  /// rate_Hz <= 0: never due; at or above the tick rate: due on every tick. A tick up to half
  /// a tick period early for its slot counts as on time (the ticks jitter).
  bool Due(std::uint64_t now_ns, double rate_Hz);
  /// Sends the next offer at once (a new scene, a stream that restarts).
  void Reset() { next_ns_ = 0; }

 private:
  double tick_Hz_;
  std::uint64_t half_tick_ns_;
  std::uint64_t next_ns_ = 0;
};

}  // namespace handshare::session
