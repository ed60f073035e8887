#pragma once
/// The world server's tick, as a list of stages over one session: members, control events,
/// contact sets, the shared objects, and what each publishes. Private to the server library:
/// it holds the DDS writers and readers; WorldServer::Run() builds it and ticks it.
#include <chrono>
#include <map>
#include <cstdint>
#include <string>
#include <vector>

#include "handshare/common/session_clock.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/dds/sample_checks.hpp"
#include "handshare/world_server/control_actions.hpp"
#include "handshare/world_server/member_registry.hpp"
#include "handshare/world_server/object_authority.hpp"
#include "handshare/world_server/world_server.hpp"

namespace handshare::server {

class ServerSession {
 public:
  using Clock = std::chrono::steady_clock;

  /// Joins the session and publishes `scene` as revision 1 with its board, or, given a resume
  /// point, the world, revision, session clock, board and body poses it holds (the nodes see
  /// the revision they already have and keep their models). Events go to `server` (printed and
  /// logged). Not real-time.
  ServerSession(WorldServer& server, const WorldServerConfig& config, dds::Participant& participant,
                scene::Scene scene, const ResumePoint* resume = nullptr);

  /// One tick at `now`, dt_s after the last: the stages below, in this order.
  void Tick(Clock::time_point now, double dt_s);

  const MemberRegistry& members() const { return members_; }
  std::uint64_t deformations_sent() const { return deformations_sent_; }
  /// Received samples refused by the checks (session/sample_checks.hpp), per topic.
  const dds::DroppedSamples& dropped() const { return dropped_; }

 private:
  // ---- the stages of a tick ----
  /// Members joining, leaving and vanishing (writers lost without a dispose).
  void TakeMembers(Clock::time_point now);
  /// Control events: logged, and their scene actions applied (ApplyControlAction).
  void TakeControlEvents();
  /// The users' contact sets, for ownership claims and the shared deformables.
  void TakeContactSets(Clock::time_point now);
  /// One step of the shared objects, and what it publishes: owners, poses, deformations.
  void StepObjects(Clock::time_point now, double dt_s);

  /// True when `reason` is empty; else the sample is dropped, counted and (rate-limited) named.
  bool Accepted(std::string_view topic, std::string_view sender, const std::string& reason) {
    return dropped_.Accept(topic, sender, reason, [this](const std::string& line) { server_.Say(line); });
  }
  /// Publishes the scene as its next revision.
  void PublishScene();
  /// Publishes the members present (SessionRoster): a node that hears this server but never
  /// one of them can tell, and join again.
  void PublishRoster();
  static constexpr std::size_t kMaxRoster = 64;  // the IDL's bound
  /// Records where the session is (world, revision, clock, board) in the session log.
  void LogState();
  /// Every published rigid-body state, a row each (--pose-trace).
  void TracePoses(const std::vector<msg::ObjectState>& states);
  /// Records the poses of the bodies just published (at most every kPoseLogPeriod a body).
  void LogPoses(const std::vector<msg::ObjectState>& states, Clock::time_point now);
  static constexpr std::chrono::milliseconds kPoseLogPeriod{100};
  /// Shows one board message (the board shows English for now; every scene file also holds
  /// Japanese). Transient-local keeps the newest for late joiners.
  void ShowMessage(const std::vector<scene::Message>& messages);
  /// Every control of the current world at rest, published and logged (a new world, or the
  /// session's start). Resuming a killed server's session: where its log says each control
  /// settled, published and logged again, so that a node joining later builds them there; a
  /// control the log does not place (a log written before schema version 3) stays unknown and
  /// unpublished (the nodes keep what that server published until an event changes it).
  void ResetControlStates(const ResumePoint* resume = nullptr);
  /// Records where a control settled in the session log.
  void LogControlPlace(const ControlStateRecord& record);

  WorldServer& server_;
  std::string session_;
  double tick_Hz_;  // announced in the scene state: how often contact sets are read
  common::SessionClock clock_;
  scene::Scene scene_;
  std::uint32_t revision_ = 0;
  std::uint32_t message_id_ = 0;
  std::vector<scene::Message> board_;                  // the board's message, every language
  std::vector<ControlStateRecord> control_states_;     // the current world's controls, as events left them
  std::map<std::string, Clock::time_point> pose_logged_;  // body -> when its pose was last logged
  ObjectAuthority objects_;
  MemberRegistry members_;

  dds::Writer<msg::SceneState> scene_writer_;
  dds::Writer<msg::MessageBoard> board_writer_;
  dds::Writer<msg::ControlState> control_state_writer_;
  dds::Writer<msg::ObjectState> object_writer_;
  dds::Writer<msg::Deformation> deformation_writer_;
  dds::Writer<msg::SessionRoster> roster_writer_;
  dds::Reader<msg::MemberInfo> member_reader_;
  dds::Reader<msg::ContactSet> contact_reader_;
  dds::Reader<msg::ControlEvent> control_reader_;

  std::uint64_t deformations_sent_ = 0;
  dds::DroppedSamples dropped_;
};

}  // namespace handshare::server
