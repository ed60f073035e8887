#include "server_conversions.hpp"

#include <cmath>

#include "handshare/dds/membership.hpp"
#include "handshare/session/control_events.hpp"

namespace handshare::server {

Member ToMember(const msg::MemberInfo& info) {
  return Member{info.member_id().to_string(), info.user().to_string(), dds::ToString(info.kind()),
                info.device().to_string(), info.pid(), dds::Describe(info.device_caps())};
}

std::optional<ControlInput> ToControlInput(const msg::ControlEvent& e) {
  const auto kind = session::FromMessage(e.kind());
  if (!kind) return std::nullopt;
  return ControlInput{e.control_id().to_string(), *kind, e.index(), e.user().to_string(), e.value()};
}

LoopRecord ToLoopRecord(const msg::LoopStatistics& s, std::uint64_t unix_ns) {
  LoopRecord r;
  r.unix_ns = unix_ns;
  r.node = s.node().to_string();
  r.rate_Hz = s.rate_Hz();
  r.jitter_p50_us = s.jitter_p50_us();
  r.jitter_p99_us = s.jitter_p99_us();
  r.jitter_max_us = s.jitter_max_us();
  r.step_p50_us = s.step_p50_us();
  r.step_p99_us = s.step_p99_us();
  r.steps = s.steps();
  r.overruns = s.overruns();
  r.resyncs = s.resyncs();
  r.faults = s.faults();
  r.samples_dropped = s.samples_dropped();
  r.deadline_misses = s.deadline_misses();
  r.sent_bytes_per_s = s.sent_bytes_per_s();
  return r;
}

ControlRecord ToControlRecord(const msg::ControlEvent& e, const ControlInput& input, std::uint64_t unix_ns) {
  ControlRecord record;
  record.unix_ns = unix_ns;
  record.user = input.user;
  record.control_id = input.control_id;
  record.kind = input.kind;
  record.value = e.value();
  if (std::isfinite(e.error_m())) record.error_m = e.error_m();
  return record;
}

msg::MessageBoard ToMessageBoard(const scene::Message& m, const std::string& session, std::uint32_t message_id) {
  msg::MessageBoard board;
  board.session(session);
  board.message_id(message_id);
  board.language(m.language);
  board.text(m.text);
  board.next_action(m.next_action);
  board.reading(m.reading);
  return board;
}

msg::Deformation ToDeformation(const std::string& object_id, const std::string& session,
                               const DeformationSample& sample) {
  msg::Deformation d;
  d.object_id(object_id);
  d.session(session);
  d.revision(sample.revision);
  d.keyframe(sample.keyframe);
  d.surface_node_count(sample.surface_node_count);
  d.node_ids().assign(sample.node_ids.begin(), sample.node_ids.end());
  d.u_W_m().assign(sample.u_W_m.begin(), sample.u_W_m.end());
  return d;
}

msg::ControlState ToControlState(const ControlStateRecord& r, const std::string& session) {
  msg::ControlState out;
  out.control_id(r.control_id);
  out.session(session);
  out.scene(r.scene);
  out.changes(r.changes);
  out.index(r.index);
  out.engaged(r.engaged);
  out.user(r.user);
  out.moving(r.moving);
  out.position(r.position);
  return out;
}

msg::ObjectState ToObjectState(const BodyState& body, const std::string& session, std::uint64_t stamp_ns) {
  msg::ObjectState s;
  s.object_id(body.object_id);
  s.session(session);
  s.owner(body.owner);
  s.stamp_ns(stamp_ns);
  contact::FromPose(body.X_WO, s.p_WO_m(), s.q_WO_wxyz());
  s.v_WO_m_per_s(contact::ToVec3(body.v_WO_m_per_s));
  return s;
}

msg::SessionRoster ToSessionRoster(const std::vector<std::string>& member_ids, const std::string& session) {
  msg::SessionRoster roster;
  roster.session(session);
  for (const std::string& id : member_ids) {
    if (roster.members().size() == kMaxRoster) break;
    roster.members().push_back(id);
  }
  return roster;
}

}  // namespace handshare::server
