#include "session_log_writer.hpp"

#include <algorithm>

#include "handshare/common/clock.hpp"

namespace handshare::server {

SessionLogWriter::SessionLogWriter(SessionLog& log, std::function<std::uint64_t()> unix_now)
    : log_(log), unix_now_(unix_now ? std::move(unix_now) : std::function<std::uint64_t()>(common::UnixNowNs)) {}

void SessionLogWriter::Take(std::span<const SessionEvent> events, Clock::time_point now) {
  const auto record = Overloaded{
      [&](const MemberChanged& e) { log_.OnMember(e.event.change, e.event.member, unix_now_()); },
      [&](const SceneShown& e) { log_.OnSceneChange(e.scene, e.title, unix_now_()); },
      [&](const SessionStateChanged& e) {
        SessionState st = e.state;
        st.unix_ns = unix_now_();
        log_.OnState(st);
      },
      [&](const ControlApplied& e) { log_.OnControlEvent(e.record); },
      [&](const ControlStateChanged& e) { LogPlace(e); },
      [&](const WorldEntered&) {
        log_.ForgetControlPlaces();  // the last world's
        log_.ForgetObjectPoses();
        pose_logged_.clear();
      },
      [&](const OwnershipChanged& e) {
        log_.OnOwnership(e.change.object_id, e.change.owner, ToString(e.change.reason), unix_now_());
      },
      [&](const BodyMoved& e) { LogPose(e.body, now); },
      [&](const SessionCheckpoint&) { Commit(); },
      [&](const SceneRevised& e) { log_.OnControlKinds(e.scene); },
      [&](const TurnEnded& e) {
        const std::uint64_t end = unix_now_();
        const auto turn_ns = static_cast<std::uint64_t>(std::max<std::int64_t>(0, e.turn.count()));
        log_.OnTurnEnded(TurnRecord{end >= turn_ns ? end - turn_ns : 0, end, e.member.member_id, e.member.user});
      },
      [&](const VisitAnswered& e) { log_.OnVisitAnswers(e.sent_by, e.answers, unix_now_()); },
      [&](const StationReported& e) { log_.OnLoopStatistics(e.loop); },
      [](const auto&) {},
  };
  for (const SessionEvent& event : events) std::visit(record, event);
}

void SessionLogWriter::LogPlace(const ControlStateChanged& e) {
  // Where a control settled; a hand's motion is for the screens, and a place not known here (a
  // resumed session's control no event has moved yet) is not the log's to say.
  if (!e.settled || !e.record.known) return;
  ControlPlace p;
  p.control_id = e.record.control_id;
  p.scene = e.record.scene;
  p.unix_ns = unix_now_();
  p.index = e.record.index;
  p.engaged = e.record.engaged;
  p.user = e.record.user;
  p.changes = e.record.changes;
  log_.OnControlPlace(p);
}

void SessionLogWriter::LogPose(const BodyState& body, Clock::time_point now) {
  auto& last = pose_logged_[body.object_id];
  if (now - last < kPoseLogPeriod) return;
  last = now;
  ObjectPose p;
  p.object_id = body.object_id;
  p.owner = body.owner;
  p.unix_ns = unix_now_();
  contact::FromPose(body.X_WO, p.p_WO_m, p.q_WO_wxyz);
  log_.OnObjectPose(p);
}

void SessionLogWriter::Commit() {
  if (!log_.error().empty()) return;  // failed: the session goes on without it
  try {
    log_.Flush();
  } catch (const SessionLogError&) {
    // The world server reports the log's error() once, after the tick.
  }
}

}  // namespace handshare::server
