#include "handshare/web_console/console_state.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

namespace handshare::web_console {

namespace {
const char* KindName(controls::EventKind k) {
  switch (k) {
    case controls::EventKind::kPressed: return "pressed";
    case controls::EventKind::kReleased: return "released";
    case controls::EventKind::kMoved: return "moved";
    case controls::EventKind::kPageTurned: return "page_turned";
    case controls::EventKind::kMissed: return "missed";
    case controls::EventKind::kOpened: return "opened";
    case controls::EventKind::kMoving: return "moving";
  }
  return "?";
}
}  // namespace

namespace {
// A length or a unit quaternion's component to 1e-6 (a micrometre: far below a pixel), which JSON
// then prints in a few digits.
double Micro(double x) { return std::round(x * 1e6) * 1e-6; }
}  // namespace

std::string HandsJson(const std::map<std::string, HandView>& hands, const hiro::HiroModel* hiro_model) {
  using nlohmann::json;
  json list = json::array();
  for (const auto& [user, h] : hands) {
    // The figure, once per document: what the screens draw of this hand.
    const figure::HandParts parts = figure::DrawnHand(h.device, hiro_model);
    json boxes = json::array();
    for (const figure::Box& b : parts.boxes) {
      boxes.push_back({Micro(b.p_W.x()), Micro(b.p_W.y()), Micro(b.p_W.z()), Micro(b.half_extents_m.x()),
                       Micro(b.half_extents_m.y()), Micro(b.half_extents_m.z()), Micro(b.q_WB.w()), Micro(b.q_WB.x()),
                       Micro(b.q_WB.y()), Micro(b.q_WB.z())});
    }
    json spheres = json::array();
    for (const figure::Sphere& b : parts.spheres) {
      spheres.push_back({Micro(b.p_W.x()), Micro(b.p_W.y()), Micro(b.p_W.z()), Micro(b.radius_m)});
    }
    list.push_back({{"user", h.user}, {"stamp_ns", std::to_string(h.stamp_ns)}, {"p_WH_m", h.p_WH_m}, {"q_WH_wxyz", h.q_WH_wxyz},
                    {"fingers", h.fingers}, {"p_WE_m", h.p_WE_m}, {"radius_m", h.fingertip_radius_m},
                    {"figure", {{"rgb", parts.rgb}, {"boxes", std::move(boxes)}, {"spheres", std::move(spheres)}}}});
  }
  return json{{"type", "hands"}, {"hands", std::move(list)}}.dump(-1, ' ', false, json::error_handler_t::replace);
}

ControlView DrawnControl(const scene::ControlSpec& spec, const ControlStateIn& state,
                         const std::array<double, 3>& p_WO_m, const std::array<double, 4>& q_WO_wxyz,
                         const std::vector<std::string>& languages) {
  ControlView v;
  v.id = spec.id;
  v.type = spec.type == scene::ControlType::kButton  ? "button"
           : spec.type == scene::ControlType::kArrow ? "arrow"
           : spec.type == scene::ControlType::kLever ? "lever"
                                                     : "book";
  v.index = state.index;
  v.engaged = state.engaged;
  v.moving = state.moving;
  v.position = state.position;
  v.user = state.user;
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
  X_WO.translation() = Eigen::Vector3d(p_WO_m[0], p_WO_m[1], p_WO_m[2]);
  X_WO.linear() = Eigen::Quaterniond(q_WO_wxyz[0], q_WO_wxyz[1], q_WO_wxyz[2], q_WO_wxyz[3]).normalized().toRotationMatrix();
  // As graphics_node's SceneReplica::DrawnPose: where a moving hand has it, else its detent, else
  // pressed down its travel.
  const bool lever = spec.type == scene::ControlType::kLever;
  const bool push = spec.type == scene::ControlType::kButton || spec.type == scene::ControlType::kArrow;
  const double travel_m = push ? spec.push.travel_m : 0.0;
  Eigen::Isometry3d X_WD = X_WO;
  if (state.moving && lever) {
    X_WD = X_WO * Eigen::AngleAxisd(state.position, Eigen::Vector3d::UnitX());
  } else if (state.moving && push && travel_m > 0.0) {
    X_WD = X_WO * Eigen::Translation3d(0.0, 0.0, -std::clamp(state.position, 0.0, travel_m));
  } else if (lever && state.index >= 0 && state.index < spec.lever.detents) {
    X_WD = X_WO * Eigen::AngleAxisd(spec.lever.detent_angle_rad(state.index), Eigen::Vector3d::UnitX());
  } else if (state.engaged && push) {
    X_WD = X_WO * Eigen::Translation3d(0.0, 0.0, -travel_m);
  }
  const Eigen::Quaterniond q(X_WD.linear());
  v.p_WO_m = {X_WD.translation().x(), X_WD.translation().y(), X_WD.translation().z()};
  v.q_WO_wxyz = {q.w(), q.x(), q.y(), q.z()};
  if (spec.type == scene::ControlType::kBook) {
    v.size_m = {spec.size_m.x(), spec.size_m.y(), spec.size_m.z()};
    const int page = std::max(0, state.index);
    if (state.engaged && static_cast<std::size_t>(page) < spec.page_content.size()) {
      const scene::BookPage& spread = spec.page_content[static_cast<std::size_t>(page)];
      for (const auto& language : languages) v.page_text[language] = spread.TextIn(language);
      if (!spread.image_uri.empty()) v.page_picture = "/pictures/" + spread.image_path.filename().string();
    }
  }
  return v;
}

bool ViewField::Apply(std::uint32_t revision, bool keyframe, std::span<const std::uint32_t> node_ids,
                      std::span<const float> u_W_m) {
  if (u_W_m.size() != 3 * node_ids.size()) return false;
  if (keyframe && revision_ != revision) std::fill(u_W_m_.begin(), u_W_m_.end(), std::array<float, 3>{0.0F, 0.0F, 0.0F});
  for (std::size_t i = 0; i < node_ids.size(); ++i) {
    const std::array<float, 3> u{u_W_m[3 * i], u_W_m[3 * i + 1], u_W_m[3 * i + 2]};
    if (node_ids[i] >= u_W_m_.size() || !std::isfinite(u[0]) || !std::isfinite(u[1]) || !std::isfinite(u[2])) {
      ++skipped_;
      continue;
    }
    u_W_m_[node_ids[i]] = u;
  }
  revision_ = revision;
  return true;
}

std::string BodiesJson(const std::string& scene, const std::map<std::string, BodyView>& bodies,
                       const std::vector<ControlView>& controls) {
  using nlohmann::json;
  json list = json::array();
  for (const auto& [id, b] : bodies) {
    list.push_back({{"id", id}, {"p_WO_m", b.p_WO_m}, {"q_WO_wxyz", b.q_WO_wxyz}, {"owner", b.owner}, {"stamp_ns", std::to_string(b.stamp_ns)}});
  }
  json drawn = json::array();
  for (const auto& c : controls) {
    json j = {{"id", c.id},         {"type", c.type},         {"index", c.index},         {"engaged", c.engaged},
              {"moving", c.moving}, {"position", c.position}, {"user", c.user},           {"p_WO_m", c.p_WO_m},
              {"q_WO_wxyz", c.q_WO_wxyz}};
    if (c.type == "book") {
      j["size_m"] = c.size_m;
      j["page_text"] = c.page_text;
      j["page_picture"] = c.page_picture;
    }
    drawn.push_back(std::move(j));
  }
  return json{{"type", "bodies"}, {"scene", scene}, {"bodies", std::move(list)}, {"controls", std::move(drawn)}}.dump(
      -1, ' ', false, json::error_handler_t::replace);
}

std::string DeformationJson(const std::string& scene, const std::map<std::string, ViewField>& fields) {
  using nlohmann::json;
  json objects = json::array();
  for (const auto& [id, f] : fields) {
    if (!f.revision()) continue;
    std::vector<std::uint32_t> ids;
    std::vector<long> u_um;
    for (std::size_t v = 0; v < f.vertex_count(); ++v) {
      const auto& u = f.u_W_m()[v];
      const long x = std::lround(1e6 * u[0]), y = std::lround(1e6 * u[1]), z = std::lround(1e6 * u[2]);
      if (x == 0 && y == 0 && z == 0) continue;
      ids.push_back(static_cast<std::uint32_t>(v));
      u_um.insert(u_um.end(), {x, y, z});
    }
    objects.push_back({{"id", id}, {"revision", *f.revision()}, {"vertex_count", f.vertex_count()},
                       {"ids", std::move(ids)}, {"u_um", std::move(u_um)}});
  }
  return json{{"type", "deformation"}, {"scene", scene}, {"objects", std::move(objects)}}.dump(
      -1, ' ', false, json::error_handler_t::replace);
}

std::string UserOfNode(const std::string& node) {
  const auto slash = node.rfind('/');
  return slash == std::string::npos ? node : node.substr(slash + 1);
}

std::string KindOfNode(const std::string& node) {
  static const std::pair<const char*, const char*> kPrograms[] = {
      {"haptic_node/", "haptic"}, {"graphics_node/", "graphics"}, {"audio_guide/", "audio_guide"},
      {"world_server/", "world_server"}};
  for (const auto& [prefix, kind] : kPrograms) {
    if (node.rfind(prefix, 0) == 0) return kind;
  }
  return "";
}

std::string ToJson(const ConsoleState& s, std::chrono::steady_clock::time_point now) {
  using nlohmann::json;
  json j;
  j["type"] = "state";
  j["session"] = s.session;
  j["console"] = {{"name", s.console_name},
                  {"actions_enabled", s.actions_enabled},
                  {"viewers", s.viewers},
                  {"viewers_dropped", s.viewers_dropped},
                  {"samples_refused", s.samples_refused}};
  if (s.world.known) {
    j["world"] = {{"scene", s.world.scene},       {"title", s.world.title},
                  {"revision", s.world.revision}, {"tick_Hz", s.world.tick_Hz},
                  {"gravity_z_m_per_s2", s.world.gravity_z_m_per_s2}, {"objects", s.world.objects}};
    json view = json::array();
    for (const auto& o : s.world.view) {
      view.push_back({{"id", o.id},           {"kind", o.kind},
                      {"shape", o.shape},     {"mesh", o.mesh},
                      {"p_WO_m", o.p_WO_m},   {"q_WO_wxyz", o.q_WO_wxyz},
                      {"half_extent_m", o.half_extent_m}, {"mesh_scale", o.mesh_scale},
                      {"rgb", o.rgb}});
    }
    j["world"]["view"] = std::move(view);
  } else {
    j["world"] = nullptr;
  }
  json routes = json::array();
  for (const auto& r : s.routes) {
    routes.push_back({{"world", r.world}, {"control", r.control_id}, {"event", KindName(r.kind)}, {"index", r.index}});
  }
  j["routes"] = std::move(routes);
  j["worlds"] = s.worlds;
  json table4 = json::array();
  const auto summary = [](const controls::Summary& x) { return json{{"n", x.n}, {"mean", x.mean}, {"sd", x.sd}}; };
  for (const auto& r : s.table4.Rows()) {
    table4.push_back({{"kind", r.kind},
                      {"controls", r.controls},
                      {"hits", r.tally.hits()},
                      {"misses", r.tally.misses()},
                      {"released", r.tally.released()},
                      {"error_m", summary(r.tally.error_m())},
                      {"misses_per_user", summary(r.tally.misses_per_user())}});
  }
  j["table4"] = {{"control_events", s.control_events}, {"kinds", std::move(table4)}};
  json boards = json::object();
  for (const auto& [language, b] : s.boards) {
    boards[language] = {{"message_id", b.message_id}, {"text", b.text}, {"next_action", b.next_action}};
  }
  j["boards"] = std::move(boards);
  json stations = json::array();
  for (const auto& [node, st] : s.stations) {
    stations.push_back({{"node", st.node},
                        {"user", st.user},
                        {"kind", st.kind},
                        {"device", st.device},
                        {"rate_Hz", st.rate_Hz},
                        {"jitter_p50_us", st.jitter_p50_us},
                        {"jitter_p99_us", st.jitter_p99_us},
                        {"step_p99_us", st.step_p99_us},
                        {"steps", st.steps},
                        {"overruns", st.overruns},
                        {"resyncs", st.resyncs},
                        {"faults", st.faults},
                        {"samples_dropped", st.samples_dropped},
                        {"deadline_misses", st.deadline_misses},
                        {"sent_bytes_per_s", st.sent_bytes_per_s},
                        {"age_s", std::chrono::duration<double>(now - st.received).count()}});
  }
  j["stations"] = std::move(stations);
  json members = json::array();
  for (const auto& [id, m] : s.members) members.push_back({{"user", m.user}, {"kind", m.kind}, {"device", m.device}});
  j["members"] = std::move(members);
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

}  // namespace handshare::web_console
