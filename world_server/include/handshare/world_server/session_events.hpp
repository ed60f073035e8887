#pragma once
/// What one tick of the world server's session did, as plain domain events: the tick
/// (ServerSession, world_server/src/server_session.hpp) is a function from its state and its
/// inputs (the samples taken this tick) to a list of these, and knows nothing of what becomes
/// of them. Consumers take the list, each in a file of its own (world_server/src/):
///   - the DDS publisher (session_publisher): scene state, roster, board, control states,
///     object states, deformations;
///   - the session log writer (session_log_writer): the only way from the tick into the SQLite
///     session log;
///   - the pose trace (pose_trace, --pose-trace): a CSV row per published body state;
///   - the console (console_log): the lines the operator reads.
/// No DDS: no message type and no middleware header is reachable from here.
#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "handshare/scene/scene.hpp"
#include "handshare/world_server/body_state.hpp"
#include "handshare/world_server/control_actions.hpp"
#include "handshare/world_server/deformation_delta.hpp"
#include "handshare/world_server/member_registry.hpp"
#include "handshare/world_server/ownership_arbiter.hpp"
#include "handshare/world_server/session_log.hpp"

namespace handshare::server {

/// A line for the operator that no other event says (a refused sample, a note of the scene's
/// logic or of the models' loader, the session's first line).
struct LineSaid {
  std::string line;
};

/// A member joined, left (disposed) or vanished (lost its writers: MemberChange::kLost).
struct MemberChanged {
  MemberEvent event;
  std::size_t present = 0;  ///< members present once this tick's member changes are taken
};

/// The members present now (in the registry's order), after any change of them.
struct RosterChanged {
  std::vector<std::string> member_ids;
};

/// A new revision of the scene the nodes build their worlds from.
struct SceneRevised {
  scene::Scene scene;
  std::uint32_t revision = 0;
  std::uint64_t epoch_unix_ns = 0;  ///< the session clock's origin
  double tick_Hz = 0.0;             ///< how often the server reads contact sets
};

/// The session shows world `scene` under `title` now (the start, and every revision).
struct SceneShown {
  std::string scene;
  std::string title;
};

/// Where the session is (world, revision, clock, board): what a restarted server resumes from.
/// unix_ns is left 0: whoever records it stamps it.
struct SessionStateChanged {
  SessionState state;
};

/// A board message, under one number in every language the scene has.
struct MessageSaid {
  std::uint32_t message_id = 0;
  std::vector<scene::Message> messages;
};

/// A control event of the session (a press, a move, a page, a miss; not a hand's motion).
struct ControlApplied {
  ControlRecord record;
};

/// Where a control is now. settled: where an event, or the world's start, left it (what a
/// restart must find); else where a hand is moving it (for the screens only).
struct ControlStateChanged {
  ControlStateRecord record;
  bool settled = true;
};

/// Another world begins (also a session that starts afresh): the last world's body poses and
/// control places are void.
struct WorldEntered {
  std::string scene;
};

struct OwnershipChanged {
  OwnershipChange change;
};

/// A rigid body's state to publish (owned, free and moving, or refreshed).
struct BodyMoved {
  BodyState body;
};

/// Changed surface nodes of a deformable (DeformationDelta's sample).
struct FieldChanged {
  std::string object_id;
  DeformationSample sample;
};

/// A visitor's turn is over (--visit-minutes after its join, or the operator ended it); the
/// board's message follows (not when the operator restarted the tour: its first world's does).
struct TurnEnded {
  Member member;
  std::chrono::nanoseconds turn{};  ///< how long it lasted
  double minutes = 0.0;             ///< the turn's length it was given
  std::string ended_by;             ///< "": its time ran out; else the operator's console
};

/// A visitor's questionnaire, as a console (`sent_by`) sent it.
struct VisitAnswered {
  std::string sent_by;
  controls::VisitAnswers answers;
};

/// A station's loop statistics, checked, for the log.
struct StationReported {
  LoopRecord loop;
};

/// Control events and what they did are complete: a server killed after this point must find
/// them on restart (the log commits now, not at its next period).
struct SessionCheckpoint {};

using SessionEvent = std::variant<LineSaid, MemberChanged, RosterChanged, SceneRevised, SceneShown,
                                  SessionStateChanged, MessageSaid, ControlApplied, ControlStateChanged, WorldEntered,
                                  OwnershipChanged, BodyMoved, FieldChanged, SessionCheckpoint, TurnEnded, VisitAnswered,
                                  StationReported>;

/// A visitor made of lambdas, one per kind of event a consumer takes (and `auto` for the rest):
/// std::visit(Overloaded{[](const BodyMoved& e) {...}, [](const auto&) {}}, event).
template <class... Fs>
struct Overloaded : Fs... {
  using Fs::operator()...;
};

/// A consumer of the tick's events.
class SessionEventSink {
 public:
  using Clock = std::chrono::steady_clock;
  virtual ~SessionEventSink() = default;
  /// The events of one tick (or of the session's start), in the order the tick produced them;
  /// `now` is the tick's time. Called once per tick, on the tick's thread.
  virtual void Take(std::span<const SessionEvent> events, Clock::time_point now) = 0;
};

}  // namespace handshare::server
