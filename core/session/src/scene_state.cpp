#include "handshare/session/scene_state.hpp"

namespace handshare::session {

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

}  // namespace handshare::session
