#include "handshare/web_console/console_state.hpp"

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

std::string HandsJson(const std::map<std::string, HandView>& hands) {
  using nlohmann::json;
  json list = json::array();
  for (const auto& [user, h] : hands) {
    list.push_back({{"user", h.user}, {"fingers", h.fingers}, {"p_WE_m", h.p_WE_m}, {"radius_m", h.fingertip_radius_m}});
  }
  return json{{"type", "hands"}, {"hands", std::move(list)}}.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string UserOfNode(const std::string& node) {
  const auto slash = node.rfind('/');
  return slash == std::string::npos ? node : node.substr(slash + 1);
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
  json boards = json::object();
  for (const auto& [language, b] : s.boards) {
    boards[language] = {{"message_id", b.message_id}, {"text", b.text}, {"next_action", b.next_action}};
  }
  j["boards"] = std::move(boards);
  json stations = json::array();
  for (const auto& [node, st] : s.stations) {
    stations.push_back({{"node", st.node},
                        {"user", st.user},
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
                        {"age_s", std::chrono::duration<double>(now - st.received).count()}});
  }
  j["stations"] = std::move(stations);
  json members = json::array();
  for (const auto& [id, m] : s.members) members.push_back({{"user", m.user}, {"kind", m.kind}, {"device", m.device}});
  j["members"] = std::move(members);
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

}  // namespace handshare::web_console
