#pragma once
/// Received samples are checked before they touch a simulation: finite numbers, magnitudes a
/// hand, a body or a deformation can have, sizes within bounds, the right session. A sample
/// that fails is dropped whole, never applied, and counted (DroppedSamples); the check says
/// what is wrong and where ("fingers[2].u_O_m[1] is nan"), for the node's log.
///
/// What these checks do not decide: whether an object id exists in the local models. A
/// contact set naming an object of another world is normal around a world change and is
/// skipped where the models are (PeerContacts::ForEach), not counted as bad.
/// Not real-time (the bridge thread, the server's tick, the graphics thread).
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <utility>
#include <string>
#include <string_view>

#include "handshare/dds/messages.hpp"

namespace handshare::dds {

/// Bounds of what a sample may say (SI). Generous: they reject corrupt or hostile values,
/// not unusual motion.
struct SampleBounds {
  double max_position_m = 100.0;          ///< |p| of any point in W (a contact's: in its object's frame)
  double max_displacement_m = 0.1;        ///< |u| imposed on or shown by a deformable
  double max_force_N = 1000.0;            ///< |f| of a contact force
  double max_speed_m_per_s = 100.0;       ///< |v| of a body
  double max_angular_speed_rad_per_s = 1000.0;
  double max_fingertip_radius_m = 0.05;
  double max_gravity_m_per_s2 = 100.0;
  double max_rate_Hz = 10000.0;           ///< a reader's announced rate (view_Hz, tick_Hz)
};

/// "" when the sample may be applied, else what is wrong with it and where.
std::string CheckContactSet(const msg::ContactSet& s, std::string_view session, const SampleBounds& b = {});
std::string CheckObjectState(const msg::ObjectState& s, std::string_view session, const SampleBounds& b = {});
std::string CheckSceneState(const msg::SceneState& s, std::string_view session, const SampleBounds& b = {});
std::string CheckControlEvent(const msg::ControlEvent& s, std::string_view session);
/// A visitor's questionnaire: session, sender and visitor named, every score 0 (not answered)
/// or 1..7, at least one answered.
std::string CheckVisitAnswers(const msg::VisitAnswers& s, std::string_view session);
/// An operator's command: session and sender named, a known kind, the world named for
/// GO_TO_WORLD and the visitor for END_TURN (each of `[a-z0-9_]` / a user name's characters).
std::string CheckOperatorCommand(const msg::OperatorCommand& s, std::string_view session);
std::string CheckControlState(const msg::ControlState& s, std::string_view session);
std::string CheckSessionRoster(const msg::SessionRoster& s, std::string_view session);
std::string CheckDeviceState(const msg::DeviceState& s, std::string_view session, const SampleBounds& b = {});
/// A desk's input (graphics_node --input desk): the target within max_position_m, a unit
/// quaternion, each closure in [0, 1].
std::string CheckDeskInput(const msg::DeskInput& s, std::string_view session, const SampleBounds& b = {});
/// Also: 3 displacements per node id, ids below surface_node_count when it is given.
std::string CheckDeformation(const msg::Deformation& s, std::string_view session, const SampleBounds& b = {});
std::string CheckMessageBoard(const msg::MessageBoard& s, std::string_view session);
std::string CheckMemberInfo(const msg::MemberInfo& s, std::string_view session);
/// A node's loop statistics: session, node named, every rate, time and byte rate finite,
/// non-negative and at most 1e9.
std::string CheckLoopStatistics(const msg::LoopStatistics& s, std::string_view session);

/// Dropped samples of one node, per topic, with the first reason seen for each.
class DroppedSamples {
 public:
  /// Counts one dropped sample of `topic` from `sender`. Returns the line to print for the first
  /// bad sample of each sender on each topic (up to kNamedSenders senders a topic) and for every 1000th of
  /// a topic, else "" (a flood prints a line per 1000 samples, not one per sample).
  std::string Count(std::string_view topic, std::string_view sender, const std::string& reason);
  /// True when `reason` is empty (the sample may be applied); else counts it and passes the
  /// line to print, if any, to `say`.
  bool Accept(std::string_view topic, std::string_view sender, const std::string& reason,
              const std::function<void(const std::string&)>& say) {
    if (reason.empty()) return true;
    if (const std::string line = Count(topic, sender, reason); !line.empty()) say(line);
    return false;
  }
  std::uint64_t total() const { return total_; }
  std::uint64_t of(std::string_view topic) const;
  /// "contact_set 12, object_state 3" ("none" when nothing was dropped).
  std::string Summary() const;

 private:
  static constexpr std::size_t kNamedSenders = 64;
  std::map<std::string, std::uint64_t, std::less<>> by_topic_;
  std::set<std::pair<std::string, std::string>> named_;  // (topic, sender) already named
  std::map<std::string, std::size_t> named_per_topic_;
  std::uint64_t total_ = 0;
};

}  // namespace handshare::dds
