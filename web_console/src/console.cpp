#include "handshare/web_console/console.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "handshare/common/data_dir.hpp"
#include "handshare/common/shutdown.hpp"
#include "handshare/dds/membership.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/dds/name_binding.hpp"
#include "handshare/dds/sample_checks.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/session/control_events.hpp"
#include "handshare/web_console/console_state.hpp"
#include "handshare/web_console/web_server.hpp"
#include "handshare/web_console/world_routes.hpp"

namespace handshare::web_console {

namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kPushPeriod = std::chrono::milliseconds(200);  // at most 5 states a second to viewers
constexpr auto kHeartbeat = std::chrono::seconds(1);          // at least one a second (stations age)
constexpr auto kStationForgotten = std::chrono::seconds(30);  // no statistics this long: gone

std::string ErrorJson(const std::string& error) {
  return nlohmann::json{{"error", error}}.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

// LoopStatistics has no check in the DDS layer yet: the console reads it alone.
std::string CheckLoopStatistics(const msg::LoopStatistics& s, const std::string& session) {
  if (s.session().to_string() != session) return "session '" + s.session().to_string() + "' is not this session";
  if (s.node().size() == 0) return "empty node";
  const double values[] = {s.rate_Hz(), s.jitter_p50_us(), s.jitter_p99_us(), s.jitter_max_us(), s.step_p50_us(),
                           s.step_p99_us()};
  for (const double v : values) {
    if (!std::isfinite(v) || v < 0.0 || v > 1e9) return "a rate or time that is negative, not finite or above 1e9";
  }
  return {};
}

std::string Hex(const dds::SampleMeta::Key& key) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  for (const auto b : key) {
    out += kDigits[b >> 4];
    out += kDigits[b & 15];
  }
  return out;
}

std::string Join(const std::vector<WorldRoute>& routes) {
  std::string out;
  for (const auto& r : routes) out += (out.empty() ? "" : ", ") + r.world;
  return out.empty() ? "nothing" : out;
}

}  // namespace

ListenAddress ParseListen(const std::string& text) {
  std::string address;
  std::string port;
  if (!text.empty() && text.front() == '[') {
    const auto close = text.find("]:");
    if (close == std::string::npos) throw std::invalid_argument("--listen '" + text + "': expected [IPv6]:PORT");
    address = text.substr(1, close - 1);
    port = text.substr(close + 2);
  } else {
    const auto colon = text.rfind(':');
    if (colon == std::string::npos || text.find(':') != colon) {
      throw std::invalid_argument("--listen '" + text + "': expected ADDR:PORT (an IPv6 address in brackets)");
    }
    address = text.substr(0, colon);
    port = text.substr(colon + 1);
  }
  if (address.empty()) throw std::invalid_argument("--listen '" + text + "': no address");
  if (port.empty() || port.size() > 5 || !std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; }) ||
      std::stoi(port) > 65535) {
    throw std::invalid_argument("--listen '" + text + "': the port is not 0 to 65535");
  }
  return ListenAddress{address, static_cast<std::uint16_t>(std::stoi(port))};
}

std::filesystem::path WwwDir() {
  const auto& installed = common::InstalledDataDir();
  return installed.empty() ? std::filesystem::path(HANDSHARE_WEB_SOURCE_DIR) / "www" : installed / "www";
}

Console::Console(ConsoleConfig config) : config_(std::move(config)) {}

int Console::Run() {
  const std::string& name = config_.name;
  const auto say = [&name](const std::string& line) {
    std::printf("[web_console %s] %s\n", name.c_str(), line.c_str());
    std::fflush(stdout);
  };
  // Everything the command line gives is checked before the session is joined.
  const ListenAddress listen = ParseListen(config_.listen);
  const std::string token = config_.token_file.empty() ? std::string() : ReadTokenFile(config_.token_file);
  const std::filesystem::path www = config_.www_dir.empty() ? WwwDir() : config_.www_dir;
  const std::string session = config_.where.session;

  dds::Participant participant(config_.where, "web_console/" + name);
  // The console joins as a screen that reads no device states (view_Hz 0): the IDL has no kind
  // of its own for it yet (docs/web_console.md, "Not done yet").
  dds::MemberAnnouncement member(participant, name, msg::NODE_GRAPHICS);
  auto scene_reader = dds::MakeReader<msg::SceneState>(participant, dds::topics::kSceneState);
  auto board_reader = dds::MakeReader<msg::MessageBoard>(participant, dds::topics::kMessageBoard);
  auto stats_reader = dds::MakeReader<msg::LoopStatistics>(participant, dds::topics::kLoopStatistics);
  auto member_reader = dds::MakeReader<msg::MemberInfo>(participant, dds::topics::kMemberInfo);
  auto events = dds::MakeWriter<msg::ControlEvent>(participant, dds::topics::kControlEvent);

  std::mutex mutex;  // guards state (the DDS thread writes it, the web thread reads it)
  ConsoleState state;
  state.session = session;
  state.console_name = name;
  state.actions_enabled = !token.empty();

  WebServerConfig web;
  web.address = listen.address;
  web.port = listen.port;
  web.tls_cert = config_.tls_cert;
  web.tls_key = config_.tls_key;
  web.token = token;
  web.max_connections = config_.max_connections;
  web.files = {{"/", www / "index.html"},
               {"/operator", www / "operator.html"},
               {"/static/operator.js", www / "operator.js"},
               {"/static/console.css", www / "console.css"}};

  const auto state_json = [&] {
    std::lock_guard lock(mutex);
    return ToJson(state, Clock::now());
  };
  const auto change_world = [&](const WorldRequest& r) -> ActionReply {
    WorldRoute route;
    std::string from;
    {
      std::lock_guard lock(mutex);
      if (!state.world.known) return {503, ErrorJson("no world yet: the world server has not been heard")};
      from = state.world.scene;
      const WorldRoute* found = FindRoute(state.routes, r.world);
      if (found == nullptr) {
        if (r.world == from) return {409, ErrorJson("the session is in '" + from + "' already")};
        const auto names = scene::SceneNames();
        if (std::find(names.begin(), names.end(), r.world) == names.end()) {
          return {404, ErrorJson("no world '" + r.world + "'")};
        }
        return {409, ErrorJson("'" + r.world + "' is not linked from '" + from + "' (it links to " +
                               Join(state.routes) + ")")};
      }
      route = *found;
    }
    msg::ControlEvent e;
    e.session(session);
    e.user(name);
    e.control_id(route.control_id);
    e.kind(session::ToMessage(route.kind));
    e.index(route.index);
    e.value(route.index >= 0 ? route.index : 0.0);
    e.stamp_ns(static_cast<std::uint64_t>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count()));
    events.Write(e);
    say("the operator sends the session from '" + from + "' to '" + r.world + "' (control " + route.control_id + ")");
    return {202, nlohmann::json{{"world", r.world}, {"control", route.control_id}, {"from", from}}.dump()};
  };
  WebServer server(web, state_json, change_world);
  say(std::string("listening on ") + (server.tls() ? "https://" : "http://") +
      (listen.address.find(':') != std::string::npos ? "[" + listen.address + "]" : listen.address) + ":" +
      std::to_string(server.port()) + " (the operator's page: /operator; actions " +
      (token.empty() ? "off: no --token-file" : "need the token") + ")");

  dds::SampleMeta meta;
  dds::DroppedSamples dropped;
  const auto sender = [](const dds::SampleMeta& m) { return "participant " + dds::ParticipantOf(m.writer); };
  // Takes every new sample into the state; true if anything changed.
  const auto take = [&]() {
    bool changed = false;
    std::lock_guard lock(mutex);
    msg::SceneState scene;
    while (scene_reader.TakeNext(scene, meta)) {
      if (!meta.valid_data ||
          !dropped.Accept("scene_state", sender(meta), dds::CheckSceneState(scene, session), say)) {
        continue;
      }
      WorldView& w = state.world;
      const std::string scene_name = scene.scene().to_string();
      const bool new_world = !w.known || w.scene != scene_name;
      w.known = true;
      w.scene = scene_name;
      w.revision = scene.revision();
      w.tick_Hz = scene.tick_Hz();
      w.gravity_z_m_per_s2 = scene.gravity_W_m_per_s2()[2];
      w.objects = scene.objects().size();
      if (new_world) {
        try {
          const scene::Scene file = scene::LoadSceneByName(scene_name, scene::DefaultSceneDir(), {.load_meshes = false});
          w.title = file.title;
          state.routes = WorldRoutes(file);
        } catch (const std::exception& e) {
          w.title.clear();
          state.routes.clear();
          say("cannot read the world '" + scene_name + "' (" + e.what() + "): no world changes from it");
        }
      }
      char line[160];
      std::snprintf(line, sizeof line, "world '%s' revision %u (server tick %.0f Hz)", scene_name.c_str(),
                    scene.revision(), static_cast<double>(scene.tick_Hz()));
      say(std::string(line) + (new_world ? ": links to " + Join(state.routes) : ""));
      changed = true;
    }
    msg::MessageBoard board;
    while (board_reader.TakeNext(board, meta)) {
      if (!meta.valid_data ||
          !dropped.Accept("message_board", sender(meta), dds::CheckMessageBoard(board, session), say)) {
        continue;
      }
      state.boards[board.language().to_string()] =
          BoardView{board.message_id(), board.text().to_string(), board.next_action().to_string()};
      changed = true;
    }
    msg::MemberInfo info;
    while (member_reader.TakeNext(info, meta)) {
      const std::string key = Hex(meta.instance);
      if (!meta.valid_data) {
        if (meta.instance_state != dds::InstanceState::kAlive) changed |= state.members.erase(key) > 0;
        continue;
      }
      if (!dropped.Accept("member_info", sender(meta), dds::CheckMemberInfo(info, session), say)) continue;
      if (info.leaving()) {
        changed |= state.members.erase(key) > 0;
        continue;
      }
      state.members[key] = MemberRow{info.user().to_string(), dds::ToString(info.kind()), info.device().to_string()};
      changed = true;
    }
    msg::LoopStatistics stats;
    const auto now = Clock::now();
    while (stats_reader.TakeNext(stats, meta)) {
      if (!meta.valid_data ||
          !dropped.Accept("loop_statistics", sender(meta), CheckLoopStatistics(stats, session), say)) {
        continue;
      }
      StationStats& st = state.stations[stats.node().to_string()];
      st.node = stats.node().to_string();
      st.user = UserOfNode(st.node);
      st.rate_Hz = stats.rate_Hz();
      st.jitter_p50_us = stats.jitter_p50_us();
      st.jitter_p99_us = stats.jitter_p99_us();
      st.step_p99_us = stats.step_p99_us();
      st.steps = stats.steps();
      st.overruns = stats.overruns();
      st.resyncs = stats.resyncs();
      st.faults = stats.faults();
      st.samples_dropped = stats.samples_dropped();
      st.received = now;
      st.device.clear();
      for (const auto& [key, m] : state.members) {
        if (m.user == st.user && m.kind == "haptic") st.device = m.device;
      }
      changed = true;
    }
    changed |= std::erase_if(state.stations, [&](const auto& s) { return now - s.second.received > kStationForgotten; }) > 0;
    state.samples_refused = dropped.total();
    return changed;
  };

  const auto start = Clock::now();
  auto last_push = Clock::time_point{};
  bool dirty = true;
  while (!common::ShutdownRequested()) {
    if (config_.where.duration.count() > 0 && Clock::now() - start >= config_.where.duration) break;
    scene_reader.WaitForData(std::chrono::milliseconds(50));
    dirty |= take();
    const auto now = Clock::now();
    if ((dirty && now - last_push >= kPushPeriod) || now - last_push >= kHeartbeat) {
      const WebServerCounts counts = server.counts();
      std::string json;
      {
        std::lock_guard lock(mutex);
        state.viewers = counts.viewers;
        state.viewers_dropped = counts.viewers_dropped;
        json = ToJson(state, now);
      }
      server.Broadcast(std::move(json));
      last_push = now;
      dirty = false;
    }
  }
  const WebServerCounts c = server.counts();
  char line[256];
  std::snprintf(line, sizeof line,
                "served %llu requests (%llu refused), %llu viewers (%llu dropped for not keeping up), %llu bytes of "
                "state to viewers",
                static_cast<unsigned long long>(c.requests), static_cast<unsigned long long>(c.refused),
                static_cast<unsigned long long>(c.viewers_total), static_cast<unsigned long long>(c.viewers_dropped),
                static_cast<unsigned long long>(c.bytes_sent));
  say(line);
  say("samples refused: " + dropped.Summary());
  say(participant.TrafficSummary());
  return 0;
}

}  // namespace handshare::web_console
