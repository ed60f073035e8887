#pragma once
/// The world server's session as a function from its state and its inputs to domain events
/// (session_events.hpp): members, control events, contact sets and the shared objects, a stage
/// each. It reads no reader and writes no writer: SampleIntake (sample_intake.hpp) takes the
/// samples into TickInputs, and the events go to the consumers (the DDS publisher, the session
/// log writer, the pose trace, the console). WorldServer::Run() builds them and ticks it.
/// Private to the server library. Not real-time.
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "handshare/common/session_clock.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/dds/sample_checks.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/controls/operator_command.hpp"
#include "handshare/world_server/control_actions.hpp"
#include "handshare/world_server/member_registry.hpp"
#include "handshare/world_server/object_authority.hpp"
#include "handshare/world_server/session_events.hpp"
#include "handshare/world_server/session_log.hpp"
#include "handshare/world_server/visit_turns.hpp"

namespace handshare::server {

/// A member-info sample, or the change of its instance, as taken.
struct MemberInput {
  enum class Kind {
    kAnnounced,  ///< valid data of an alive instance: `member` is who it announces
    kLeaving,    ///< valid data saying "leaving": a clean leave, said in data
    kDisposed,   ///< the instance was disposed (a clean leave)
    kNoWriters,  ///< the instance lost its writers
  };
  Kind kind = Kind::kAnnounced;
  InstanceKey instance{};
  InstanceKey writer{};
  Member member;        ///< kAnnounced only
  std::string refused;  ///< kAnnounced: why the sample check refused it ("" accepted)
};

/// A writer of member info that went away (killed, lost) or came back (a partition healed).
struct WriterInput {
  InstanceKey writer{};
  bool alive = false;
};

/// A control event as taken (valid data only).
struct ControlEventInput {
  std::string user;     ///< who it names (the sender, for the dropped-sample lines)
  InstanceKey writer{};
  std::string refused;  ///< why the sample check refused it ("" accepted)
  ControlInput input;   ///< accepted samples only
  ControlRecord record; ///< its row for the log, stamped when taken (accepted samples only)
};

/// A contact set as taken (valid data only). Still the wire's type: ObjectAuthority and
/// session::PeerContacts take it as it is.
struct ContactSetInput {
  msg::ContactSet set;
  InstanceKey writer{};
  std::string refused;  ///< why the sample check refused it ("" accepted)
};

/// A visitor's questionnaire as taken (valid data only).
struct VisitAnswersInput {
  std::string user;     ///< who sent it (a console's member name)
  InstanceKey writer{};
  std::string refused;  ///< why the sample check refused it ("" accepted)
  controls::VisitAnswers answers;  ///< accepted samples only
};

/// An operator's command as taken (valid data only).
struct OperatorCommandInput {
  std::string user;     ///< who sent it (a console's member name)
  InstanceKey writer{};
  std::string refused;  ///< why the sample check refused it ("" accepted)
  controls::OperatorCommand command;  ///< accepted samples only
};

/// A station's loop statistics as taken (valid data only).
struct LoopStatisticsInput {
  std::string node;
  std::string refused;  ///< why the sample check refused it ("" accepted)
  LoopRecord loop;      ///< accepted samples only
};

/// What one tick takes, in the order it takes it.
struct TickInputs {
  std::vector<MemberInput> members;
  std::vector<WriterInput> member_writers;  ///< after the member samples
  std::vector<ControlEventInput> controls;
  std::vector<ContactSetInput> contacts;
  std::vector<VisitAnswersInput> visits;
  std::vector<OperatorCommandInput> commands;
  std::vector<LoopStatisticsInput> stations;
  void clear() {
    commands.clear();
    stations.clear();
    visits.clear();
    members.clear();
    member_writers.clear();
    controls.clear();
    contacts.clear();
  }
};

struct ServerSessionConfig {
  std::string session;
  int domain_id = 0;       ///< for the session's first line only
  double tick_Hz = 60.0;   ///< announced in the scene state: how often contact sets are read
  ObjectAuthorityOptions objects;
  SceneLoader load = LoadWorld;  ///< the worlds a control's action opens, and a resumed one
  /// A visitor's turn (a haptic member's, from its join); zero: turns never end by themselves.
  std::chrono::nanoseconds visit_turn{0};
  /// The world a tour starts in (world_server --scene): where the operator's "restart the
  /// tour" takes the session. Empty: the world the session was made with.
  std::string tour_start;
};

class ServerSession {
 public:
  using Clock = std::chrono::steady_clock;
  using Events = std::vector<SessionEvent>;

  /// A session on `scene`, or, given a resume point (a killed server's log), on the world,
  /// revision, session clock, board, control places and body poses it holds. Emits nothing:
  /// Start() does.
  ServerSession(ServerSessionConfig config, scene::Scene scene, const ResumePoint* resume = nullptr);

  /// The session's start: the scene as its next revision, the roster, the world's controls at
  /// rest and the board. A resumed session takes this same path from the resume point's state:
  /// the same revision and message number again and the controls where the log placed them, so
  /// the consumers publish, log and print a resumed start as they do a fresh one (nodes that
  /// already have that revision and message change nothing).
  Events Start();

  /// One tick at `now`, dt_s after the last: the stages below, in this order.
  Events Tick(const TickInputs& in, Clock::time_point now, double dt_s);

  const MemberRegistry& members() const { return members_; }
  /// Received samples refused (the sample checks, or a user's name from another participant).
  const dds::DroppedSamples& dropped() const { return dropped_; }
  const scene::Scene& scene() const { return scene_; }
  const ObjectAuthority& objects() const { return objects_; }

 private:
  // ---- the stages of a tick ----
  /// Members joining, leaving and vanishing (writers lost without a dispose).
  void TakeMembers(const TickInputs& in, Clock::time_point now, Events& out);
  /// Control events: their records, and their scene actions applied (ApplyControlAction).
  void TakeControlEvents(const TickInputs& in, Events& out);
  /// The users' contact sets, for ownership claims and the shared deformables.
  void TakeContactSets(const TickInputs& in, Clock::time_point now, Events& out);
  /// One step of the shared objects, and what it publishes: owners, poses, deformations.
  void StepObjects(Clock::time_point now, double dt_s, Events& out);
  /// Visitors' questionnaires, for the log.
  void TakeVisitAnswers(const TickInputs& in, Events& out);
  /// The operator's commands: another world, the tour again, a visitor's turn ended.
  void TakeOperatorCommands(const TickInputs& in, Clock::time_point now, Events& out);
  /// Stations' loop statistics, for the log.
  void TakeStations(const TickInputs& in, Events& out);
  /// Visitors' turns that are over: each said on the board, once.
  void EndTurns(Clock::time_point now, Events& out);
  /// What a world change, a new gravity or title did (a control's action or the operator's):
  /// the controls of a new world at rest, the models rebuilt, the revision, the notes and the
  /// board.
  void ApplyOutcome(const ControlOutcome& outcome, Events& out);

  /// True when `reason` is empty; else the sample is dropped, counted and (rate-limited) named.
  bool Accepted(std::string_view topic, std::string_view sender, const std::string& reason, Events& out);
  /// The scene as its next revision, and where the session is now.
  void ReviseScene(Events& out);
  /// The members present.
  void SayRoster(Events& out);
  /// One board message in every language the scene has, and where the session is now.
  void ShowMessage(const std::vector<scene::Message>& messages, Events& out);
  /// Where the session is (world, revision, clock, board).
  SessionState State() const;
  /// Every control of the current world at rest (a new world, or the session's start). Resuming
  /// a killed server's session: where its log says each control settled; a control the log does
  /// not place (a log written before schema version 3) stays unknown and unsaid (the nodes keep
  /// what that server published until an event changes it).
  void ResetControlStates(const std::vector<ControlPlace>* places, Events& out);
  /// The controls where a killed server's log placed them (those the world has, at places
  /// they can have).
  void PlaceControls(const std::vector<ControlPlace>& places, Events& out);

  ServerSessionConfig config_;
  common::SessionClock clock_;
  scene::Scene scene_;
  std::string first_world_;  // the world the session was made with (or resumed in)
  std::optional<ResumePoint> resume_;  // until Start()
  std::uint32_t revision_ = 0;
  std::uint32_t message_id_ = 0;
  std::vector<scene::Message> board_;              // the board's message, every language
  std::vector<ControlStateRecord> control_states_; // the current world's controls, as events left them
  ObjectAuthority objects_;
  MemberRegistry members_;
  VisitTurns turns_;
  dds::DroppedSamples dropped_;
};

}  // namespace handshare::server
