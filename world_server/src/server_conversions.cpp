#include "server_conversions.hpp"

#include <cmath>

#include "handshare/dds/membership.hpp"
#include "handshare/session/control_events.hpp"

namespace handshare::server {

msg::SceneState ToSceneState(const scene::Scene& s, const std::string& session, std::uint32_t revision,
                             std::uint64_t session_epoch_unix_ns, double tick_Hz) {
  msg::SceneState out;
  out.tick_Hz(static_cast<float>(tick_Hz));
  out.session(session);
  out.scene(s.name);
  out.revision(revision);
  out.session_epoch_unix_ns(session_epoch_unix_ns);
  out.gravity_W_m_per_s2({s.gravity_W_m_per_s2.x(), s.gravity_W_m_per_s2.y(), s.gravity_W_m_per_s2.z()});
  for (const auto& o : s.objects) {
    msg::SceneObject m;
    m.object_id(o.id);
    m.kind(o.kind == scene::ObjectKind::kRigid        ? msg::OBJECT_RIGID
           : o.kind == scene::ObjectKind::kDeformable ? msg::OBJECT_DEFORMABLE
                                                      : msg::OBJECT_CONTROL);
    m.shape(o.shape == scene::Shape::kSphere ? "sphere" : o.shape == scene::Shape::kBox ? "box" : "mesh");
    m.mesh_uri(o.mesh_uri);
    m.p_WO_m({o.p_WO_m.x(), o.p_WO_m.y(), o.p_WO_m.z()});
    m.q_WO_wxyz({o.q_WO.w(), o.q_WO.x(), o.q_WO.y(), o.q_WO.z()});
    m.half_extent_m({o.half_extent_m.x(), o.half_extent_m.y(), o.half_extent_m.z()});
    m.mass_kg(o.mass_kg);
    m.rgb({o.rgb[0], o.rgb[1], o.rgb[2]});
    out.objects().push_back(m);
  }
  return out;
}

Member ToMember(const msg::MemberInfo& info) {
  return Member{info.member_id().to_string(), info.user().to_string(), dds::ToString(info.kind()),
                info.device().to_string(), info.pid()};
}

std::optional<ControlInput> ToControlInput(const msg::ControlEvent& e) {
  const auto kind = session::FromMessage(e.kind());
  if (!kind) return std::nullopt;
  return ControlInput{e.control_id().to_string(), *kind, e.index(), e.user().to_string()};
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
  return out;
}

}  // namespace handshare::server
