#include "handshare/world_server/world_server.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <thread>

#include "handshare/common/clock.hpp"
#include "handshare/common/shutdown.hpp"
#include "handshare/dds/membership.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/world_server/member_registry.hpp"
#include "handshare/world_server/shared_world.hpp"

namespace handshare::world {

namespace {

msg::SceneState ToMessage(const scene::Scene& s, const std::string& session, unsigned revision) {
  msg::SceneState out;
  out.session(session);
  out.scene(s.name);
  out.revision(revision);
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

Member FromMessage(const msg::MemberInfo& info) {
  return Member{info.member_id().to_string(), info.user().to_string(),
                dds::ToString(info.kind()), info.device().to_string(), info.pid()};
}

std::string HostName() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "";
  return name;
}

}  // namespace

WorldServer::WorldServer(WorldServerConfig config)
    : config_(std::move(config)), start_(std::chrono::steady_clock::now()) {}

WorldServer::~WorldServer() = default;

void WorldServer::Print(const std::string& line) {
  const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::printf("[world_server %8.3f s] %s\n", t, line.c_str());
  std::fflush(stdout);
}

bool WorldServer::CheckLog() {
  if (!log_ || log_failed_) return !log_failed_;
  if (const std::string error = log_->error(); !error.empty()) {
    log_failed_ = true;
    Print("session log failed, the session goes on without it: " + error);
  }
  return !log_failed_;
}

void WorldServer::OnControlEvent(const ControlRecord& event) {
  char line[200];
  std::snprintf(line, sizeof line, "control %s: %s by %s (value %.3f, error %s)", event.control_id.c_str(),
                ToString(event.kind), event.user.c_str(), event.value,
                event.error_m ? (std::to_string(1e3 * *event.error_m).substr(0, 5) + " mm").c_str() : "-");
  Print(line);
  if (log_) log_->OnControlEvent(event);
}

void WorldServer::OnSceneChange(const std::string& scene, const std::string& title) {
  Print("scene '" + scene + "': " + title);
  if (log_) log_->OnSceneChange(scene, title, common::UnixNowNs());
}

void WorldServer::OnMemberEvent(const MemberEvent& event, std::size_t present) {
  const Member& m = event.member;
  std::ostringstream line;
  line << "member " << ToString(event.change) << ": user=" << m.user << " kind=" << m.kind;
  if (!m.device.empty()) line << " device=" << m.device;
  line << " pid=" << m.pid << " present=" << present;
  Print(line.str());
  if (log_) log_->OnMember(event.change, m, common::UnixNowNs());
}

void WorldServer::OnOwnershipChange(const OwnershipChange& change) {
  Print("object '" + change.object_id + "': owner '" + change.previous_owner + "' -> '" + change.owner + "' (" +
        ToString(change.reason) + ")");
  if (log_) log_->OnOwnership(change.object_id, change.owner, ToString(change.reason), common::UnixNowNs());
}

int WorldServer::Run() {
  using Clock = std::chrono::steady_clock;
  start_ = Clock::now();
  scene::Scene scene = scene::LoadSceneByName(config_.scene);
  // The log opens once the scene is known to load (a bad scene name leaves no empty session
  // behind) and before any DDS entity exists (a bad log file keeps us out of the session).
  if (!config_.log_file.empty() && !log_) {
    log_ = std::make_unique<SessionLog>(
        config_.log_file, SessionStart{config_.where.session, config_.where.domain_id, HostName(),
                                       static_cast<std::int64_t>(getpid()), common::UnixNowNs()});
  }

  dds::Participant participant(config_.where.domain_id, config_.where.session, "world_server", config_.where.qos_file);
  auto scene_writer = dds::MakeWriter<msg::SceneState>(participant, dds::topics::kSceneState);
  auto board_writer = dds::MakeWriter<msg::MessageBoard>(participant, dds::topics::kMessageBoard);
  auto member_reader = dds::MakeReader<msg::MemberInfo>(participant, dds::topics::kMemberInfo);
  auto contact_reader = dds::MakeReader<msg::ContactSet>(participant, dds::topics::kContactSet);
  auto object_writer = dds::MakeWriter<msg::ObjectState>(participant, dds::topics::kObjectState);
  auto deformation_writer = dds::MakeWriter<msg::Deformation>(participant, dds::topics::kDeformation);

  const auto start = start_;
  auto log = [&](const std::string& line) { Print(line); };

  if (log_) log("session log " + log_->file().string() + ": session #" + std::to_string(log_->session_id()));
  std::uint32_t revision = 1;
  scene_writer.Write(ToMessage(scene, config_.where.session, revision));
  log("session '" + config_.where.session + "' on domain " + std::to_string(config_.where.domain_id) +
      ": scene '" + scene.name + "' (" + std::to_string(scene.objects.size()) + " objects)");
  OnSceneChange(scene.name, scene.title);

  // The shared world: ownership, free bodies, deformations (models built on a loader thread).
  SharedWorldOptions shared_options;
  if (!config_.cache_dir.empty()) shared_options.models.cache_dir = config_.cache_dir;
  shared_options.dump_dir = config_.dump_dir;
  shared_options.delta.threshold_m = config_.deformation_threshold_m;
  SharedWorld shared(config_.where.session, shared_options);
  shared.SetScene(scene);

  // The message board shows one message at a time, in English (the Japanese texts are in the
  // scene files); transient-local keeps the newest for late joiners.
  unsigned message_id = 0;
  auto show = [&](const std::vector<scene::Message>& messages) {
    for (const auto& m : messages) {
      if (m.language != "en") continue;
      msg::MessageBoard board;
      board.session(config_.where.session);
      board.message_id(++message_id);
      board.language(m.language);
      board.text(m.text);
      board.next_action(m.next_action);
      board_writer.Write(board);
      log("message board #" + std::to_string(message_id) + ": " + m.text);
      return;
    }
  };
  show(scene.messages);

  // Control events from the haptic nodes: logged, and their scene actions applied here, the
  // one place that owns the world (navigation, gravity, the board).
  auto control_reader = dds::MakeReader<msg::ControlEvent>(participant, dds::topics::kControlEvent);
  auto apply = [&](const msg::ControlEvent& e) {
    const std::string id = e.control_id().to_string();
    const scene::ControlSpec* spec = nullptr;
    for (const auto& c : scene.controls) {
      if (c.id == id) spec = &c;
    }
    if (spec == nullptr) return;  // a control of a world already left
    const scene::Action* action = nullptr;
    const auto index = static_cast<std::size_t>(std::max<std::int32_t>(0, e.index()));
    switch (e.kind()) {
      case msg::CONTROL_PRESSED:
        if (spec->type == scene::ControlType::kButton || spec->type == scene::ControlType::kArrow) action = &spec->action;
        break;
      case msg::CONTROL_OPENED:
        action = &spec->action;
        break;
      case msg::CONTROL_MOVED:
        if (e.index() >= 0 && index < spec->detent_actions.size()) action = &spec->detent_actions[index];
        break;
      case msg::CONTROL_PAGE_TURNED:
        if (e.index() >= 0 && index < spec->page_actions.size()) action = &spec->page_actions[index];
        break;
      default:
        break;
    }
    if (action == nullptr || action->empty()) return;
    // A copy: going to another world replaces the scene that holds the control and its action.
    const scene::Action taken = *action;
    action = &taken;
    if (!action->goto_scene.empty()) {
      try {
        scene = scene::LoadSceneByName(action->goto_scene);
      } catch (const std::exception& ex) {
        log(std::string("control ") + id + ": cannot go to '" + action->goto_scene + "': " + ex.what());
        return;
      }
      scene_writer.Write(ToMessage(scene, config_.where.session, ++revision));
      shared.SetScene(scene);
      log("control " + id + " by " + e.user().to_string() + ": scene '" + scene.name + "' (revision " +
          std::to_string(revision) + ")");
      OnSceneChange(scene.name, scene.title);
      show(scene.messages);
    }
    bool changed = false;
    if (action->set_gravity) {
      scene.gravity_W_m_per_s2 = action->gravity_W_m_per_s2;
      changed = true;
    }
    if (!action->title.empty()) {
      scene.title = action->title;
      changed = true;
    }
    if (changed) {
      scene_writer.Write(ToMessage(scene, config_.where.session, ++revision));
      if (action->set_gravity) shared.SetScene(scene);
      char line[200];
      std::snprintf(line, sizeof line, "control %s by %s: gravity %.2f m/s^2, '%s' (revision %u)", id.c_str(),
                    e.user().to_string().c_str(), scene.gravity_W_m_per_s2.z(), scene.title.c_str(), revision);
      log(line);
      OnSceneChange(scene.name, scene.title);
    }
    if (!action->messages.empty()) show(action->messages);
  };

  MemberRegistry members;
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / config_.tick_Hz));
  auto next = Clock::now();
  Clock::time_point last_tick{};
  std::uint64_t deformations_sent = 0;
  msg::MemberInfo info;
  dds::SampleMeta meta;
  while (!common::ShutdownRequested()) {
    if (config_.where.duration.count() > 0 && Clock::now() - start >= config_.where.duration) break;
    std::vector<MemberEvent> events;
    while (member_reader.TakeNext(info, meta)) {
      std::optional<MemberEvent> event;
      if (meta.valid_data && meta.instance_state == dds::InstanceState::kAlive) {
        event = members.OnInfo(meta.instance, meta.writer, FromMessage(info));
      } else if (meta.instance_state != dds::InstanceState::kAlive) {
        event = members.OnGone(meta.instance, meta.instance_state == dds::InstanceState::kDisposed);
      }
      if (event) events.push_back(*event);
    }
    // Writers that vanished without disposing: killed processes, lost hosts.
    dds::SampleMeta::Key lost_writer;
    while (member_reader.TakeLostWriter(lost_writer)) {
      for (auto& e : members.OnWriterLost(lost_writer)) events.push_back(e);
    }
    for (const auto& event : events) {
      OnMemberEvent(event, members.present().size());
      if (event.change != MemberChange::kJoined) {
        shared.OnUserGone(event.member.user, Clock::now());
      } else if (event.member.kind == dds::ToString(msg::NODE_GRAPHICS)) {
        shared.RequestKeyframes();  // a new spectator gets the whole deformed surfaces
      }
    }
    msg::ControlEvent control;
    dds::SampleMeta control_meta;
    while (control_reader.TakeNext(control, control_meta)) {
      if (!control_meta.valid_data) continue;
      ControlRecord record;
      record.unix_ns = common::UnixNowNs();
      record.user = control.user().to_string();
      record.control_id = control.control_id().to_string();
      switch (control.kind()) {
        case msg::CONTROL_RELEASED: record.kind = ControlKind::kReleased; break;
        case msg::CONTROL_MOVED: record.kind = ControlKind::kMoved; break;
        case msg::CONTROL_PAGE_TURNED: record.kind = ControlKind::kPageTurned; break;
        case msg::CONTROL_MISSED: record.kind = ControlKind::kMissed; break;
        default: record.kind = ControlKind::kPressed; break;  // pressed, and a book's opening
      }
      record.value = control.value();
      if (std::isfinite(control.error_m())) record.error_m = control.error_m();
      OnControlEvent(record);
      apply(control);
    }
    // The users' contacts, then one step of the shared world, and what it publishes.
    msg::ContactSet contact_set;
    dds::SampleMeta contact_meta;
    while (contact_reader.TakeNext(contact_set, contact_meta)) {
      if (contact_meta.valid_data) shared.OnContactSet(contact_set, Clock::now());
    }
    const auto now = Clock::now();
    const double dt = last_tick == Clock::time_point{} ? 1.0 / config_.tick_Hz
                                                       : std::chrono::duration<double>(now - last_tick).count();
    last_tick = now;
    TickOutput out = shared.Tick(now, std::min(dt, 0.1));
    for (const auto& note : out.notes) log(note);
    for (const auto& change : out.ownership) OnOwnershipChange(change);
    for (const auto& state : out.states) object_writer.Write(state);
    for (const auto& [object_id, sample] : out.deformations) {
      msg::Deformation d;
      d.object_id(object_id);
      d.session(config_.where.session);
      d.revision(sample.revision);
      d.keyframe(sample.keyframe);
      d.surface_node_count(sample.surface_node_count);
      d.node_ids().assign(sample.node_ids.begin(), sample.node_ids.end());
      d.u_W_m().assign(sample.u_W_m.begin(), sample.u_W_m.end());
      deformation_writer.Write(d);
      ++deformations_sent;
    }
    CheckLog();
    next += period;
    if (Clock::now() > next + 5 * period) next = Clock::now();
    std::this_thread::sleep_until(next);
  }
  log("shutting down: " + std::to_string(members.joined_total()) + " members joined, " +
      std::to_string(members.present().size()) + " still present, " + std::to_string(deformations_sent) +
      " deformation samples sent");
  if (log_) {
    // Members still present stay open in the log: the report shows them "present at end".
    log_->End(common::UnixNowNs());
    try {
      log_->Flush();
      if (!log_failed_) log("session log: session #" + std::to_string(log_->session_id()) + " written");
    } catch (const SessionLogError& e) {
      if (!log_failed_) log(std::string("session log failed: ") + e.what());
      log_failed_ = true;
    }
    if (log_->dropped_rows() > 0) log("session log: " + std::to_string(log_->dropped_rows()) + " rows dropped");
  }
  return log_failed_ ? 1 : 0;
}

}  // namespace handshare::world
