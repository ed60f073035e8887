#include "server_session.hpp"

#include <algorithm>

#include "handshare/dds/membership.hpp"

namespace handshare::server {

namespace {

// The scene a resume point describes (its world, with the gravity and title it had then).
scene::Scene ResumedScene(scene::Scene fallback, const ResumePoint* resume, const SceneLoader& load) {
  if (resume == nullptr) return fallback;
  scene::Scene s = load(resume->state.scene);
  s.gravity_W_m_per_s2 = contact::AsVector(resume->state.gravity_W_m_per_s2);
  s.title = resume->state.title;
  return s;
}

}  // namespace

ServerSession::ServerSession(ServerSessionConfig config, scene::Scene scene, const ResumePoint* resume)
    : config_(std::move(config)),
      clock_(resume ? common::SessionClock::FromEpoch(resume->state.epoch_unix_ns) : common::SessionClock()),
      scene_(ResumedScene(std::move(scene), resume, config_.load)),
      first_world_(scene_.name),
      objects_(config_.session, config_.objects, clock_),
      turns_(std::chrono::duration_cast<Clock::duration>(config_.visit_turn)) {
  if (resume == nullptr) return;
  resume_ = *resume;
  // The same revision and message number again: nodes that have them change nothing.
  revision_ = resume->state.revision - 1;
  message_id_ = resume->state.message_id - 1;
  for (const auto& p : resume->poses) {
    // A body its owner held: kept for that owner's claim for 2 s (a participant lease of 1 s
    // and rediscovery, 0.3 s measured), so it is not dropped and re-grabbed. A logged pose
    // nobody can trust (not finite, no rotation) is not placed: the body starts where the
    // scene puts it.
    Eigen::Isometry3d X_WO;
    if (!contact::ToPose(p.p_WO_m, p.q_WO_wxyz, X_WO)) continue;
    objects_.PlaceBody(p.object_id, X_WO, p.owner, std::chrono::seconds(2));
  }
}

ServerSession::Events ServerSession::Start() {
  // One path for a fresh start and a resumed one (issue 43): the resume point set the numbers
  // (constructor) and places the controls here; the events are the same kinds either way, so
  // what the consumers do with a resumed start cannot drift from what they do with a fresh one.
  Events out;
  ReviseScene(out);
  SayRoster(out);
  out.push_back(LineSaid{"session '" + config_.session + "' on domain " + std::to_string(config_.domain_id) +
                         ": scene '" + scene_.name + "' (" + std::to_string(scene_.objects.size()) + " objects)"});
  out.push_back(SceneShown{scene_.name, scene_.title});
  objects_.SetScene(scene_);
  ResetControlStates(resume_ ? &resume_->controls : nullptr, out);
  ShowMessage(resume_ && !resume_->state.board.empty() ? resume_->state.board : scene_.messages, out);
  resume_.reset();
  return out;
}

ServerSession::Events ServerSession::Tick(const TickInputs& in, Clock::time_point now, double dt_s) {
  Events out;
  TakeMembers(in, now, out);
  TakeControlEvents(in, out);
  TakeContactSets(in, now, out);
  StepObjects(now, dt_s, out);
  TakeVisitAnswers(in, out);
  TakeOperatorCommands(in, now, out);
  TakeStations(in, out);
  EndTurns(now, out);
  return out;
}

bool ServerSession::Accepted(std::string_view topic, std::string_view sender, const std::string& reason, Events& out) {
  return dropped_.Accept(topic, sender, reason, [&out](const std::string& line) { out.push_back(LineSaid{line}); });
}

void ServerSession::TakeMembers(const TickInputs& in, Clock::time_point now, Events& out) {
  std::vector<MemberEvent> events;
  for (const MemberInput& m : in.members) {
    std::optional<MemberEvent> event;
    switch (m.kind) {
      case MemberInput::Kind::kLeaving:
      case MemberInput::Kind::kDisposed: event = members_.OnGone(m.instance, /*disposed=*/true); break;
      case MemberInput::Kind::kNoWriters: event = members_.OnGone(m.instance, /*disposed=*/false); break;
      case MemberInput::Kind::kAnnounced:
        if (!Accepted("member_info", m.member.user, m.refused, out)) continue;
        if (const std::string other = members_.CheckAuthor(m.member.user, m.writer); !other.empty()) {
          // The newest announcement names the user's participant (a restarted node's must win
          // before the old one's lease runs out); say so, for a station that takes a name.
          out.push_back(LineSaid{"member " + m.member.user + " announced again by another participant (" + other +
                                 "): samples in this name are taken from the new one"});
        }
        event = members_.OnInfo(m.instance, m.writer, m.member);
        break;
    }
    if (event) events.push_back(*event);
  }
  // Writers that vanished without disposing (killed processes, lost hosts), and writers back
  // after a partition healed: their members rejoin, once each.
  for (const WriterInput& w : in.member_writers) {
    for (auto& e : w.alive ? members_.OnWriterRegained(w.writer) : members_.OnWriterLost(w.writer)) {
      events.push_back(e);
    }
  }
  if (!events.empty()) SayRoster(out);
  const std::size_t present = members_.present().size();
  for (const auto& event : events) {
    turns_.OnMember(event.change, event.member, now);
    out.push_back(MemberChanged{event, present});
    if (event.change != MemberChange::kJoined) {
      objects_.OnUserGone(event.member.user, now);
    } else if (event.member.kind == dds::ToString(msg::NODE_GRAPHICS)) {
      objects_.RequestKeyframes();  // a new spectator gets the whole deformed surfaces
    }
  }
}

void ServerSession::SayRoster(Events& out) {
  RosterChanged roster;
  for (const Member& m : members_.present()) roster.member_ids.push_back(m.member_id);
  out.push_back(std::move(roster));
}

void ServerSession::TakeControlEvents(const TickInputs& in, Events& out) {
  bool applied = false;
  for (const ControlEventInput& e : in.controls) {
    if (!Accepted("control_event", e.user, e.refused, out) ||
        !Accepted("control_event", e.user, members_.CheckAuthor(e.user, e.writer), out)) {
      continue;
    }
    if (e.input.kind == controls::EventKind::kMoving) {
      // Motion (up to 25 a second while a hand moves a control): for the screens, not the log.
      if (const ControlStateRecord* changed = UpdateControlState(control_states_, e.input)) {
        out.push_back(ControlStateChanged{*changed, /*settled=*/false});
      }
      continue;
    }
    out.push_back(ControlApplied{e.record});
    // Where the event left its control, before its action (which may leave the world).
    if (const ControlStateRecord* changed = UpdateControlState(control_states_, e.input)) {
      out.push_back(ControlStateChanged{*changed, /*settled=*/true});
    }
    ApplyOutcome(ApplyControlAction(scene_, e.input, config_.load), out);
    applied = true;
  }
  // A control event and what it did are committed before the tick goes on (a few a minute):
  // a server killed right after still leaves them in the log, and a restart resumes from them.
  if (applied) out.push_back(SessionCheckpoint{});
}

void ServerSession::ApplyOutcome(const ControlOutcome& outcome, Events& out) {
  if (outcome.world_changed) ResetControlStates(nullptr, out);
  if (outcome.world_changed || outcome.gravity_changed) objects_.SetScene(scene_);
  if (outcome.revised) ReviseScene(out);
  for (const auto& note : outcome.notes) {
    out.push_back(LineSaid{outcome.revised ? note + " (revision " + std::to_string(revision_) + ")" : note});
  }
  if (outcome.revised) out.push_back(SceneShown{scene_.name, scene_.title});
  for (const auto& board : outcome.boards) ShowMessage(board, out);
}

void ServerSession::TakeContactSets(const TickInputs& in, Clock::time_point now, Events& out) {
  for (const ContactSetInput& c : in.contacts) {
    const std::string user = c.set.user().to_string();
    if (Accepted("contact_set", user, c.refused, out) &&
        Accepted("contact_set", user, members_.CheckAuthor(user, c.writer), out)) {
      objects_.OnContactSet(c.set, now);
    }
  }
}

void ServerSession::StepObjects(Clock::time_point now, double dt_s, Events& out) {
  TickOutput step = objects_.Tick(now, dt_s);
  for (auto& note : step.notes) out.push_back(LineSaid{std::move(note)});
  for (auto& change : step.ownership) out.push_back(OwnershipChanged{std::move(change)});
  for (auto& body : step.bodies) out.push_back(BodyMoved{std::move(body)});
  for (auto& [object_id, sample] : step.deformations) out.push_back(FieldChanged{object_id, std::move(sample)});
}

void ServerSession::TakeVisitAnswers(const TickInputs& in, Events& out) {
  bool taken = false;
  for (const VisitAnswersInput& v : in.visits) {
    if (!Accepted("visit_answers", v.user, v.refused, out) ||
        !Accepted("visit_answers", v.user, members_.CheckAuthor(v.user, v.writer), out)) {
      continue;
    }
    out.push_back(VisitAnswered{v.user, v.answers});
    taken = true;
  }
  // A visitor's answers are few and not to be lost with a killed server.
  if (taken) out.push_back(SessionCheckpoint{});
}

void ServerSession::TakeStations(const TickInputs& in, Events& out) {
  for (const LoopStatisticsInput& s : in.stations) {
    if (Accepted("loop_statistics", s.node, s.refused, out)) out.push_back(StationReported{s.loop});
  }
}

void ServerSession::EndTurns(Clock::time_point now, Events& out) {
  const auto ended = turns_.TakeEnded(now);
  const double minutes = std::chrono::duration<double, std::ratio<60>>(config_.visit_turn).count();
  for (const auto& e : ended) {
    out.push_back(TurnEnded{e.member, std::chrono::duration_cast<std::chrono::nanoseconds>(e.turn), minutes, ""});
    ShowMessage(TurnOverMessages(e.member.user, minutes), out);
  }
  if (!ended.empty()) out.push_back(SessionCheckpoint{});
}

void ServerSession::TakeOperatorCommands(const TickInputs& in, Clock::time_point now, Events& out) {
  bool applied = false;
  const double minutes = std::chrono::duration<double, std::ratio<60>>(config_.visit_turn).count();
  for (const OperatorCommandInput& c : in.commands) {
    if (!Accepted("operator_command", c.user, c.refused, out) ||
        !Accepted("operator_command", c.user, members_.CheckAuthor(c.user, c.writer), out)) {
      continue;
    }
    const std::string by = std::string("operator command ") + controls::ToString(c.command.action) + " by " + c.user;
    switch (c.command.action) {
      case controls::OperatorAction::kGoToWorld:
        ApplyOutcome(GoToWorld(scene_, c.command.world, by, config_.load), out);
        break;
      case controls::OperatorAction::kRestartTour: {
        // The tour's first world afresh (also when the session is in it: its controls at rest
        // and its first message again), and every present visitor's turn from now.
        const std::string start = config_.tour_start.empty() ? first_world_ : config_.tour_start;
        ApplyOutcome(GoToWorld(scene_, start, by, config_.load), out);
        for (const auto& e : turns_.Restart(members_.present(), now)) {
          out.push_back(TurnEnded{e.member, std::chrono::duration_cast<std::chrono::nanoseconds>(e.turn), minutes, c.user});
        }
        break;
      }
      case controls::OperatorAction::kEndTurn: {
        const auto ended = turns_.EndNow(c.command.visitor, now);
        if (!ended) {
          out.push_back(LineSaid{by + ": " + c.command.visitor + " has no turn to end (not a present visitor, or it ended)"});
          continue;
        }
        out.push_back(TurnEnded{ended->member, std::chrono::duration_cast<std::chrono::nanoseconds>(ended->turn), minutes,
                                c.user});
        ShowMessage(TurnOverMessages(ended->member.user, std::nullopt), out);
        break;
      }
    }
    applied = true;
  }
  // Like a control event's action: committed before the tick goes on.
  if (applied) out.push_back(SessionCheckpoint{});
}

void ServerSession::ResetControlStates(const std::vector<ControlPlace>* places, Events& out) {
  control_states_ = InitialControlStates(scene_, /*known=*/places == nullptr);
  if (places == nullptr) {
    out.push_back(WorldEntered{scene_.name});  // the last world's places are void
  } else {
    PlaceControls(*places, out);
  }
  for (const auto& r : control_states_) {
    if (r.known) out.push_back(ControlStateChanged{r, /*settled=*/true});
  }
}

void ServerSession::PlaceControls(const std::vector<ControlPlace>& places, Events& out) {
  for (const ControlPlace& place : places) {
    if (place.scene != scene_.name) continue;
    // A place the control cannot have (the scene file changed since, or the log was edited)
    // leaves it unknown, as a log without places does.
    const auto spec = std::find_if(scene_.controls.begin(), scene_.controls.end(),
                                   [&](const scene::ControlSpec& c) { return c.id == place.control_id; });
    if (spec == scene_.controls.end()) continue;
    if (!IndexFits(*spec, place.index)) {
      out.push_back(LineSaid{"control '" + place.control_id + "': the session log places it at index " +
                             std::to_string(place.index) + ", which it does not have: left where the nodes have it"});
      continue;
    }
    for (ControlStateRecord& r : control_states_) {
      if (r.control_id != place.control_id) continue;
      r.index = place.index;
      r.engaged = place.engaged;
      r.user = place.user;
      r.changes = place.changes;
      r.known = true;
    }
  }
}

void ServerSession::ReviseScene(Events& out) {
  out.push_back(SceneRevised{scene_, ++revision_, clock_.EpochUnixNs(), config_.tick_Hz});
  out.push_back(SessionStateChanged{State()});
}

void ServerSession::ShowMessage(const std::vector<scene::Message>& messages, Events& out) {
  if (messages.empty()) return;
  // Every language of the message, under one number: each screen and guide shows its own.
  board_ = messages;
  out.push_back(MessageSaid{++message_id_, messages});
  out.push_back(SessionStateChanged{State()});
}

SessionState ServerSession::State() const {
  SessionState st;
  st.scene = scene_.name;
  st.title = scene_.title;
  st.revision = revision_;
  st.gravity_W_m_per_s2 = contact::ToVec3(scene_.gravity_W_m_per_s2);
  st.epoch_unix_ns = clock_.EpochUnixNs();
  st.message_id = message_id_;
  st.board = board_;
  return st;
}

}  // namespace handshare::server
