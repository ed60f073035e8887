#pragma once
/// The haptic node's conversions between DDS samples and the haptic world's types: pure
/// functions (no participant, no I/O, no clock read: times come in as arguments), unit-tested
/// without DDS (haptic_node/test/bridge_conversions_test.cpp). Private to the node library:
/// they are the DDS boundary, so they may name the generated message types; the public
/// headers of haptic_node/include never do.
#include <cstdint>
#include <map>
#include <string>

#include <Eigen/Geometry>

#include "desk_device.hpp"
#include "handshare/common/latency_histogram.hpp"
#include "handshare/common/periodic_loop.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/haptic/haptic_snapshot.hpp"
#include "handshare/haptic/scene_renderer.hpp"
#include "handshare/session/contact_deadband.hpp"
#include "handshare/session/peer_contacts.hpp"
#include "handshare/world/scene_models.hpp"

namespace handshare::haptic {

/// The device state viewers get from one haptic snapshot (user and session are set once).
void ToDeviceState(const HapticSnapshot& s, msg::DeviceState& out);
/// The device's capabilities as its member announces them (msg::DeviceCaps).
msg::DeviceCaps ToDeviceCaps(const DeviceCapabilities& c);

/// The desk device's target from a checked desk input (dds::CheckDeskInput), taken at
/// received_ns on the steady clock.
DeskTarget ToDeskTarget(const msg::DeskInput& in, std::uint64_t received_ns);

/// The loop statistics sample of the haptic loop's statistics and its fault count.
void ToLoopStatistics(const common::LoopStats& s, std::uint64_t faults, msg::LoopStatistics& out);

/// The dynamic body this hand claims for simulating it: the one it grasps (world::IsGrasp on
/// the forces on the body), else the one it touches with the largest force, or -1. The world
/// server gives a claimed free body to its claimant; a body held by another stays theirs.
std::int32_t ClaimedBody(const ContactReport& r);

/// Whether the report's fingers hold `object` in a grasp (world::IsGrasp on their forces on it).
bool HandGrasps(const ContactReport& r, std::int32_t object);

/// A peer whose newest contact set, not faded out at `now`, holds `object_id` in a grasp
/// (world::IsGrasp on its fingers' forces on it; a touch is not a grasp), or "" when none.
std::string PeerGrasping(const session::PeerContacts& peers, const std::string& object_id,
                         session::PeerContacts::Clock::time_point now);

/// The body this node owns while its hand lets go of it and another user's hand grasps it.
/// Remote hands put no force on a rigid body, so simulated on, the body would fall out of that
/// hand for the release grace and the round trip until the world server's hand-over reaches
/// the other user's node. Instead it is held still where this hand let go of it (followed at
/// rest, so it is also reported there) until the server's hand-over arrives, this hand grasps
/// it again or the other hand lets go.
class HandOverHold {
 public:
  /// One bridge tick: `owned` is OwnedBody(), `report` this hand's newest report, `grasper`
  /// PeerGrasping() for the owned body ("" none). While the hold lasts the held body is
  /// appended to `followed` at rest (received at now_ns). Returns true when a hold begins.
  bool Update(std::int32_t owned, const ContactReport& report, const std::string& grasper, std::uint64_t now_ns,
              FollowedBodies& followed);
  std::int32_t held() const noexcept { return object_; }
  /// How many holds began.
  std::uint64_t holds() const noexcept { return holds_; }

 private:
  std::int32_t object_ = -1;
  ContactReport::Body at_{};
  std::uint64_t holds_ = 0;
};

/// The pose a reported body is at (its quaternion normalized).
Eigen::Isometry3d PoseOf(const ContactReport::Body& body);

/// A published rigid-body state as this node received it.
struct ReceivedBody {
  msg::ObjectState state;
  std::uint64_t received_ns = 0;  ///< when it arrived (this host's steady clock)
};
using ReceivedBodies = std::map<std::string, ReceivedBody>;  ///< object id -> newest

/// The dynamic bodies of `models` this hand follows: every received body that is not owned by
/// `user` (at most kMaxReportedBodies; unknown and static objects are skipped).
FollowedBodies ToFollowedBodies(const ReceivedBodies& bodies, const std::string& user,
                                const world::SceneModels& models);

/// The body the world server gave `user` to simulate (object index), or -1.
std::int32_t OwnedBody(const ReceivedBodies& bodies, const std::string& user, const world::SceneModels& models);

/// The peers' contacts on this scene's deformables that have not faded out at `now`, not faded,
/// with their arrival times and the fade law: the haptic thread fades them at each step
/// (rigid bodies move by their owner's published pose instead; at most kMaxRemoteContacts).
RemoteContacts ToRemoteContacts(const session::PeerContacts& peers, const world::SceneModels& models,
                                session::PeerContacts::Clock::time_point now);

/// Fills `out`'s fingers, grasp claim and simulated body from a contact report. `owned` is
/// OwnedBody(); `radius_m` the fingertip radius. Returns whether the set says something the
/// others need: a finger touches, or the hand grasps or simulates a body (an owner keeps
/// reporting its body's pose after letting go, until the server frees it).
bool ToContactSet(const ContactReport& report, const world::SceneModels& models, std::int32_t owned,
                  double radius_m, msg::ContactSet& out);

/// What the haptic step judges its next reports by (SceneRenderer::SetSentReference), once
/// `sent`, made from `report` with `owned` as ToContactSet's, went out through `deadband` at
/// sent_ns.
SentReference ToSentReference(const ContactReport& report, const msg::ContactSet& sent, std::int32_t owned,
                              const session::DeadbandConfig& deadband, std::uint64_t sent_ns);

}  // namespace handshare::haptic
