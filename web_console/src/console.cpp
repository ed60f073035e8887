#include "handshare/web_console/console.hpp"

#include <algorithm>
#include <fstream>
#include <limits>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <optional>
#include <set>
#include <unistd.h>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "handshare/common/data_dir.hpp"
#include "handshare/common/shutdown.hpp"
#include "handshare/dds/membership.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/dds/name_binding.hpp"
#include "handshare/dds/sample_checks.hpp"
#include "handshare/hiro/hiro_model.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/session/control_events.hpp"
#include "handshare/session/operator_command.hpp"
#include "handshare/session/visit_answers_message.hpp"
#include "handshare/web_console/console_state.hpp"
#include "handshare/web_console/gltf_export.hpp"
#include "handshare/web_console/web_server.hpp"
#include "handshare/web_console/world_routes.hpp"

namespace handshare::web_console {

namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kPushPeriod = std::chrono::milliseconds(200);  // at most 5 states a second to viewers
constexpr auto kHeartbeat = std::chrono::seconds(1);          // at least one a second (stations age)
constexpr auto kStationForgotten = std::chrono::seconds(30);  // no statistics this long: gone
constexpr auto kHandsPeriod = std::chrono::milliseconds(50);  // the view's hands and bodies: at most 20 a second
// The view's deformed meshes: at most 10 a second (a document holds every displaced vertex of
// every deformed mesh, some 15 kB for a pressed tail: twice the rate would double the bytes).
constexpr auto kDeformationPeriod = std::chrono::milliseconds(100);
const std::vector<std::string> kLanguages = {"en", "ja"};     // the view's board and book pages
constexpr double kViewHz = 20.0;                               // announced: device states this often

std::string ErrorJson(const std::string& error) {
  return nlohmann::json{{"error", error}}.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
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

// What the 3-D view draws of the world: the scene state's objects, controls included (at rest),
// with the scene file's mesh scale; meshes by the URL of their exported .glb.
std::vector<ViewObject> ViewOf(const msg::SceneState& state, const scene::Scene* file,
                               const std::set<std::string>& exported) {
  const auto url = [&](const std::string& mesh_uri) {
    const std::string stem = std::filesystem::path(mesh_uri).stem().string();
    return exported.count(stem) > 0 ? "/meshes/" + stem + ".glb" : std::string();
  };
  std::vector<ViewObject> out;
  for (const auto& o : state.objects()) {
    ViewObject v;
    v.id = o.object_id().to_string();
    v.kind = o.kind() == msg::OBJECT_RIGID ? "rigid" : o.kind() == msg::OBJECT_DEFORMABLE ? "deformable" : "control";
    v.shape = o.shape().to_string();
    if (v.shape == "mesh") v.mesh = url(o.mesh_uri().to_string());
    for (int k = 0; k < 3; ++k) {
      v.p_WO_m[k] = o.p_WO_m()[k];
      v.half_extent_m[k] = o.half_extent_m()[k];
      v.rgb[k] = o.rgb()[k];
    }
    for (int k = 0; k < 4; ++k) v.q_WO_wxyz[k] = o.q_WO_wxyz()[k];
    if (file != nullptr) {
      for (const auto& f : file->objects) {
        if (f.id == v.id) v.mesh_scale = {f.mesh_scale.x(), f.mesh_scale.y(), f.mesh_scale.z()};
      }
    }
    out.push_back(std::move(v));
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
  // The console joins as a screen that reads device states for its 3-D view at 20 Hz: the IDL
  // has no kind of its own for it yet (docs/web_console.md, "Not done yet").
  dds::MemberAnnouncement member(participant, name, msg::NODE_GRAPHICS, "", kViewHz);
  auto scene_reader = dds::MakeReader<msg::SceneState>(participant, dds::topics::kSceneState);
  auto board_reader = dds::MakeReader<msg::MessageBoard>(participant, dds::topics::kMessageBoard);
  auto stats_reader = dds::MakeReader<msg::LoopStatistics>(participant, dds::topics::kLoopStatistics);
  auto member_reader = dds::MakeReader<msg::MemberInfo>(participant, dds::topics::kMemberInfo);
  auto device_reader = dds::MakeReader<msg::DeviceState>(participant, dds::topics::kDeviceState);
  // What the screens draw besides the scene state: moving bodies, deformations, controls' states.
  auto object_reader = dds::MakeReader<msg::ObjectState>(participant, dds::topics::kObjectState);
  auto deformation_reader = dds::MakeReader<msg::Deformation>(participant, dds::topics::kDeformation);
  auto control_reader = dds::MakeReader<msg::ControlState>(participant, dds::topics::kControlState);
  // The control events, for the paper's Table 4 live (counted as session_report counts the log).
  auto event_reader = dds::MakeReader<msg::ControlEvent>(participant, dds::topics::kControlEvent);
  auto events = dds::MakeWriter<msg::ControlEvent>(participant, dds::topics::kControlEvent);
  auto visits = dds::MakeWriter<msg::VisitAnswers>(participant, dds::topics::kVisitAnswers);
  auto commands = dds::MakeWriter<msg::OperatorCommand>(participant, dds::topics::kOperatorCommand);

  std::mutex mutex;  // guards state (the DDS thread writes it, the web thread reads it)
  ConsoleState state;
  // Every world's controls' kinds, for Table 4 by kind (a control of a scene file the console
  // cannot read counts as "unknown", as in a log that does not say).
  std::map<std::string, scene::ControlType> control_kinds;
  for (const auto& world : scene::SceneNames()) {
    try {
      for (const auto& c : scene::LoadSceneByName(world, scene::DefaultSceneDir(), {.load_meshes = false}).controls) {
        control_kinds[c.id] = c.type;
      }
    } catch (const std::exception& e) {
      say("cannot read the world '" + world + "' (" + e.what() + "): its controls count as unknown in Table 4");
    }
  }
  state.session = session;
  state.console_name = name;
  state.actions_enabled = !token.empty();
  state.worlds = scene::SceneNames();

  WebServerConfig web;
  web.address = listen.address;
  web.port = listen.port;
  web.tls_cert = config_.tls_cert;
  web.tls_key = config_.tls_key;
  web.token = token;
  web.max_connections = config_.max_connections;
  web.files = {{"/", www / "index.html"},
               {"/operator", www / "operator.html"},
               {"/static/live.js", www / "live.js"},
               {"/static/operator.js", www / "operator.js"},
               {"/visit", www / "visit.html"},
               {"/static/visit.js", www / "visit.js"},
               {"/static/console.css", www / "console.css"},
               {"/static/view.js", www / "view.js"},
               // three.js from Debian's libjs-three, at the paths its loader imports it from.
               {"/three/build/three.module.js", std::filesystem::path(HANDSHARE_THREE_DIR) / "build/three.module.js"},
               {"/three/examples/jsm/loaders/GLTFLoader.js",
                std::filesystem::path(HANDSHARE_THREE_DIR) / "examples/jsm/loaders/GLTFLoader.js"},
               {"/three/examples/jsm/controls/OrbitControls.js",
                std::filesystem::path(HANDSHARE_THREE_DIR) / "examples/jsm/controls/OrbitControls.js"}};
  // Every mesh of the assets exported once to glTF 2.0, through a folder of this process's
  // that the server reads at start and that goes right after.
  std::set<std::string> exported;
  std::map<std::string, std::size_t> vertex_counts;  // by mesh stem: what a deformation's node ids index
  const auto glb_dir = std::filesystem::temp_directory_path() / ("handshare-web-console-" + std::to_string(getpid()));
  std::filesystem::create_directories(glb_dir);
  const auto mesh_dir = common::AssetsDir() / "meshes";
  for (const auto& entry : std::filesystem::directory_iterator(mesh_dir)) {
    if (entry.path().extension() != ".obj") continue;
    const std::string stem = entry.path().stem().string();
    const GlbMesh mesh = ExportGlb(entry.path());
    std::ofstream(glb_dir / (stem + ".glb"), std::ios::binary)
        .write(mesh.glb.data(), static_cast<std::streamsize>(mesh.glb.size()));
    vertex_counts[stem] = mesh.vertex_count;
    web.files["/meshes/" + stem + ".glb"] = glb_dir / (stem + ".glb");
    exported.insert(stem);
  }
  // The books' pictures (an open book's left page), by file name (DrawnControl's page_picture).
  for (const auto& entry : std::filesystem::directory_iterator(common::AssetsDir() / "images")) {
    if (entry.path().extension() == ".png") web.files["/pictures/" + entry.path().filename().string()] = entry.path();
  }

  const auto state_json = [&] {
    std::lock_guard lock(mutex);
    return ToJson(state, Clock::now());
  };
  const auto stamp_ns = [] {
    return static_cast<std::uint64_t>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count());
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
        if (std::find(state.worlds.begin(), state.worlds.end(), r.world) == state.worlds.end()) {
          return {404, ErrorJson("no world '" + r.world + "'")};
        }
        // No control of this world goes there: the operator's own command does (the world
        // server takes it only from the console's participant).
        commands.Write(session::ToMessage({controls::OperatorAction::kGoToWorld, r.world, ""}, session, name, stamp_ns()));
        say("the operator sends the session from '" + from + "' to '" + r.world + "' (operator command: no control of '" +
            from + "' links it)");
        return {202, nlohmann::json{{"world", r.world}, {"command", "go_to_world"}, {"from", from}}.dump()};
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
    // Not a hand's touch: no distance from the control's target (the session log keeps none,
    // and Table 4's hit errors are the visitors' only).
    e.error_m(std::numeric_limits<double>::quiet_NaN());
    e.stamp_ns(stamp_ns());
    events.Write(e);
    say("the operator sends the session from '" + from + "' to '" + r.world + "' (control " + route.control_id + ")");
    return {202, nlohmann::json{{"world", r.world}, {"control", route.control_id}, {"from", from}}.dump()};
  };
  // A visitor's questionnaire (checked by ParseVisitRequest) goes to the world server, which
  // stores it in its session log; the console keeps nothing of it.
  const auto send_visit = [&](const controls::VisitAnswers& answers) -> ActionReply {
    {
      std::lock_guard lock(mutex);
      if (!state.world.known) return {503, ErrorJson("no world server heard yet: the answers would be lost")};
    }
    int answered = 0;
    for (const auto& kind : answers.scores) {
      for (auto score : kind) answered += score > 0 ? 1 : 0;
    }
    visits.Write(session::ToMessage(answers, session, name, stamp_ns()));
    say("questionnaire of visitor " + answers.visitor + " sent to the world server (" + std::to_string(answered) +
        " answers)");
    return {202, nlohmann::json{{"visitor", answers.visitor}, {"answers", answered}}.dump()};
  };
  // The operator's commands no hand can give: the tour from its first world again, a
  // visitor's turn ended now. The world server says what it did on the board and in its log.
  const auto send_command = [&](const controls::OperatorCommand& c) -> ActionReply {
    {
      std::lock_guard lock(mutex);
      if (!state.world.known) return {503, ErrorJson("no world server heard yet: the command would be lost")};
      if (c.action == controls::OperatorAction::kEndTurn &&
          std::none_of(state.members.begin(), state.members.end(),
                       [&](const auto& m) { return m.second.user == c.visitor && m.second.kind == "haptic"; })) {
        return {404, ErrorJson("no visitor '" + c.visitor + "' in the session")};
      }
    }
    commands.Write(session::ToMessage(c, session, name, stamp_ns()));
    say(std::string("operator command ") + controls::ToString(c.action) +
        (c.action == controls::OperatorAction::kEndTurn ? " (visitor " + c.visitor + ")" : "") +
        " sent to the world server");
    nlohmann::json reply{{"command", controls::ToString(c.action)}};
    if (c.action == controls::OperatorAction::kEndTurn) reply["visitor"] = c.visitor;
    return {202, reply.dump()};
  };
  std::optional<WebServer> server_or;
  try {
    server_or.emplace(web, state_json, change_world, send_visit, send_command);
  } catch (...) {
    std::filesystem::remove_all(glb_dir);
    throw;
  }
  std::filesystem::remove_all(glb_dir);
  WebServer& server = *server_or;
  say(std::to_string(exported.size()) + " meshes exported to glTF 2.0 for the view at /");
  say(std::string("listening on ") + (server.tls() ? "https://" : "http://") +
      (listen.address.find(':') != std::string::npos ? "[" + listen.address + "]" : listen.address) + ":" +
      std::to_string(server.port()) + " (the operator's page: /operator; the questionnaire: /visit; actions " +
      (token.empty() ? "off: no --token-file" : "need the token") + ")");

  // The HIRO II's model: its users' hands are drawn from their joint angles, as the screens do
  // (without the file, fitted to the fingertips like any other, as there).
  std::optional<hiro::HiroModel> hiro_model;
  try {
    hiro_model = hiro::HiroModel::Load(common::AssetsDir() / "devices" / "hiro2.json");
  } catch (const std::exception& e) {
    say(std::string("HIRO II hands are fitted to their fingertips: ") + e.what());
  }
  dds::SampleMeta meta;
  dds::DroppedSamples dropped;
  std::optional<scene::Scene> world_file;  // the current world's scene file, if the console has it
  std::map<std::string, HandView> hands;   // by DeviceState instance (its user); the DDS thread's only
  dds::NameBinding names;                  // who announced each present user (the DDS thread's only)
  bool hands_changed = false;
  // The moving parts of the current world (the DDS thread's only): bodies by object id, the
  // controls' states by control id (with the world they belong to), mesh fields by object id.
  std::map<std::string, BodyView> bodies;
  std::map<std::string, std::pair<std::string, ControlStateIn>> control_states;
  std::vector<ControlView> controls;
  std::map<std::string, ViewField> fields;
  bool bodies_changed = false;
  bool fields_changed = false;
  const auto in_world = [&](const std::string& id) -> const ViewObject* {
    for (const auto& o : state.world.view) {
      if (o.id == id) return &o;
    }
    return nullptr;
  };
  // The controls as drawn: those of the current world with a state, at the scene state's pose.
  const auto draw_controls = [&] {
    controls.clear();
    if (!world_file) return;
    for (const auto& spec : world_file->controls) {
      const auto it = control_states.find(spec.id);
      const ViewObject* o = in_world(spec.id);
      if (it == control_states.end() || it->second.first != state.world.scene || o == nullptr) continue;
      controls.push_back(DrawnControl(spec, it->second.second, o->p_WO_m, o->q_WO_wxyz, kLanguages));
    }
  };
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
          world_file = scene::LoadSceneByName(scene_name, scene::DefaultSceneDir(), {.load_meshes = false});
          w.title = world_file->title;
          state.routes = WorldRoutes(*world_file);
        } catch (const std::exception& e) {
          world_file.reset();
          w.title.clear();
          state.routes.clear();
          say("cannot read the world '" + scene_name + "' (" + e.what() + "): no world changes from it");
        }
      }
      w.view = ViewOf(scene, world_file ? &*world_file : nullptr, exported);
      // Poses and fields belong to the world they were sent for; a new revision keeps those of
      // the objects that remain.
      if (new_world) {
        bodies.clear();
        fields.clear();
      }
      std::erase_if(bodies, [&](const auto& b) { return in_world(b.first) == nullptr; });
      std::map<std::string, ViewField> kept;
      for (const auto& o : w.view) {
        if (o.mesh.empty()) continue;
        const std::size_t count = vertex_counts.at(std::filesystem::path(o.mesh).stem().string());
        const auto it = fields.find(o.id);
        kept.emplace(o.id, it != fields.end() && it->second.vertex_count() == count ? it->second : ViewField(count));
      }
      fields = std::move(kept);
      draw_controls();
      bodies_changed = fields_changed = true;
      char line[160];
      std::snprintf(line, sizeof line, "world '%s' revision %u (server tick %.0f Hz)", scene_name.c_str(),
                    scene.revision(), static_cast<double>(scene.tick_Hz()));
      say(std::string(line) + (new_world ? ": links to " + Join(state.routes) : ""));
      changed = true;
    }
    msg::ControlEvent event;
    while (event_reader.TakeNext(event, meta)) {
      if (!meta.valid_data ||
          !dropped.Accept("control_event", sender(meta), dds::CheckControlEvent(event, session), say)) {
        continue;
      }
      const auto kind = session::FromMessage(event.kind());
      if (!kind || *kind == controls::EventKind::kMoving) continue;  // motion: for the screens, not the table
      const std::string id = event.control_id().to_string();
      const auto k = control_kinds.find(id);
      state.table4.Add(id, k == control_kinds.end() ? std::nullopt : std::optional<scene::ControlType>(k->second), *kind,
                       event.user().to_string(),
                       std::isfinite(event.error_m()) ? std::optional<double>(event.error_m()) : std::nullopt);
      ++state.control_events;
      changed = true;
    }
    // Object states and deformations name objects of a world: taken once a world is known, after
    // its scene state (a late joiner may get their history first), for the objects it has.
    if (state.world.known) {
      msg::ObjectState object;
      while (object_reader.TakeNext(object, meta)) {
        if (!meta.valid_data ||
            !dropped.Accept("object_state", sender(meta), dds::CheckObjectState(object, session), say)) {
          continue;
        }
        const std::string id = object.object_id().to_string();
        if (in_world(id) == nullptr) continue;  // another world's, around a world change
        BodyView& b = bodies[id];
        for (int k = 0; k < 3; ++k) b.p_WO_m[k] = object.p_WO_m()[k];
        for (int k = 0; k < 4; ++k) b.q_WO_wxyz[k] = object.q_WO_wxyz()[k];
        b.owner = object.owner().to_string();
        b.stamp_ns = object.stamp_ns();
        bodies_changed = true;
      }
      msg::Deformation deformation;
      while (deformation_reader.TakeNext(deformation, meta)) {
        if (!meta.valid_data ||
            !dropped.Accept("deformation", sender(meta), dds::CheckDeformation(deformation, session), say)) {
          continue;
        }
        const auto it = fields.find(deformation.object_id().to_string());
        if (it == fields.end()) continue;  // not a mesh of this world
        fields_changed |= it->second.Apply(deformation.revision(), deformation.keyframe(), deformation.node_ids(),
                                           deformation.u_W_m());
      }
    }
    msg::ControlState control;
    bool controls_changed = false;
    while (control_reader.TakeNext(control, meta)) {
      if (!meta.valid_data ||
          !dropped.Accept("control_state", sender(meta), dds::CheckControlState(control, session), say)) {
        continue;
      }
      control_states[control.control_id().to_string()] = {
          control.scene().to_string(),
          ControlStateIn{control.index(), control.engaged(), control.moving(), control.position(),
                         control.user().to_string()}};
      controls_changed = true;
    }
    if (controls_changed) {
      draw_controls();
      bodies_changed = true;
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
        if (meta.instance_state != dds::InstanceState::kAlive) {
          changed |= state.members.erase(key) > 0;
          names.OnMemberGone(meta.instance);
        }
        continue;
      }
      if (!dropped.Accept("member_info", sender(meta), dds::CheckMemberInfo(info, session), say)) continue;
      if (info.leaving()) {
        changed |= state.members.erase(key) > 0;
        names.OnMemberGone(meta.instance);
        continue;
      }
      state.members[key] = MemberRow{info.user().to_string(), dds::ToString(info.kind()), info.device().to_string()};
      names.OnMember(meta.instance, info.user().to_string(), meta.writer, info.kind(), info.view_Hz(),
                     info.device().to_string());
      changed = true;
    }
    dds::WriterChange member_writer;
    while (member_reader.TakeWriterChange(member_writer)) {
      if (!member_writer.alive) names.OnWriterLost(member_writer.writer);
    }
    msg::DeviceState device;
    while (device_reader.TakeNext(device, meta)) {
      const std::string key = Hex(meta.instance);  // the user's instance: a left user's hand goes
      if (!meta.valid_data) {
        if (meta.instance_state != dds::InstanceState::kAlive) hands_changed |= hands.erase(key) > 0;
        continue;
      }
      // A hand in a present user's name from another participant than the one that announced
      // that user is not drawn (as the screens: dds::NameBinding).
      std::string bad = dds::CheckDeviceState(device, session);
      if (bad.empty()) bad = names.Check(device.user().to_string(), meta.writer);
      if (!dropped.Accept("device_state", sender(meta), bad, say)) continue;
      HandView& h = hands[key];
      h.user = device.user().to_string();
      for (int k = 0; k < 3; ++k) h.p_WH_m[k] = device.p_WH_m()[k];
      for (int k = 0; k < 4; ++k) h.q_WH_wxyz[k] = device.q_WH_wxyz()[k];
      h.fingers.clear();
      h.p_WE_m.clear();
      for (int f = 0; f < static_cast<int>(device.p_WE_m().size()); ++f) {
        if ((device.absent_fingers() >> f) & 1u) continue;
        h.fingers.push_back(f);
        h.p_WE_m.push_back({device.p_WE_m()[f][0], device.p_WE_m()[f][1], device.p_WE_m()[f][2]});
      }
      h.fingertip_radius_m = device.fingertip_radius_m();
      h.stamp_ns = device.stamp_ns();
      // All of the state's hand, for its figure (drawn once per hands document, HandsJson).
      h.device.p_WH_m = device.p_WH_m();
      h.device.q_WH_wxyz = device.q_WH_wxyz();
      for (int f = 0; f < common::kFingers; ++f) h.device.p_WE[f] = Eigen::Vector3d(device.p_WE_m()[f].data());
      h.device.absent_fingers = device.absent_fingers();
      h.device.fingertip_radius_m = device.fingertip_radius_m();
      h.device.q_hand_rad = device.q_hand_rad();
      h.device.hiro = std::any_of(state.members.begin(), state.members.end(), [&](const auto& m) {
        return m.second.user == h.user && m.second.kind == "haptic" && m.second.device == "hiro";
      });
      hands_changed = true;
    }
    msg::LoopStatistics stats;
    const auto now = Clock::now();
    while (stats_reader.TakeNext(stats, meta)) {
      if (!meta.valid_data ||
          !dropped.Accept("loop_statistics", sender(meta), dds::CheckLoopStatistics(stats, session), say)) {
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
      st.deadline_misses = stats.deadline_misses();
      st.sent_bytes_per_s = stats.sent_bytes_per_s();
      st.received = now;
      // A station is its user's member of its program's kind (alice's haptic node and alice's
      // own screen are two members named alice).
      st.kind = KindOfNode(st.node);
      st.device.clear();
      for (const auto& [key, m] : state.members) {
        if (m.user == st.user && m.kind == st.kind) st.device = m.device;
      }
      changed = true;
    }
    changed |= std::erase_if(state.stations, [&](const auto& s) { return now - s.second.received > kStationForgotten; }) > 0;
    state.samples_refused = dropped.total();
    return changed;
  };

  const auto start = Clock::now();
  auto last_push = Clock::time_point{};
  auto last_hands = Clock::time_point{};
  auto last_bodies = Clock::time_point{};
  auto last_fields = Clock::time_point{};
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
    if (hands_changed && now - last_hands >= kHandsPeriod) {
      server.Broadcast(HandsJson(hands, hiro_model ? &*hiro_model : nullptr));
      last_hands = now;
      hands_changed = false;
    }
    // Bodies and fields: when they change, and once a second while there are any (a viewer
    // that came meanwhile gets them).
    const bool any_bodies = !bodies.empty() || !controls.empty();
    if ((bodies_changed && now - last_bodies >= kHandsPeriod) || (any_bodies && now - last_bodies >= kHeartbeat)) {
      std::string scene_name;
      {
        std::lock_guard lock(mutex);
        scene_name = state.world.scene;
      }
      server.Broadcast(BodiesJson(scene_name, bodies, controls));
      last_bodies = now;
      bodies_changed = false;
    }
    const bool any_field = std::any_of(fields.begin(), fields.end(), [](const auto& f) { return f.second.revision().has_value(); });
    if ((fields_changed && now - last_fields >= kDeformationPeriod) || (any_field && now - last_fields >= kHeartbeat)) {
      std::string scene_name;
      {
        std::lock_guard lock(mutex);
        scene_name = state.world.scene;
      }
      server.Broadcast(DeformationJson(scene_name, fields));
      last_fields = now;
      fields_changed = false;
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
