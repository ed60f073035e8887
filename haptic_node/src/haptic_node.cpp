#include "handshare/haptic/haptic_node.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <iomanip>
#include <memory>
#include <stdexcept>
#include <thread>

#include "handshare/common/shutdown.hpp"
#include "handshare/dds/membership.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/common/clock.hpp"
#include "handshare/haptic/haptic_loop.hpp"
#include "handshare/haptic/replay.hpp"
#include "handshare/haptic/scene_renderer.hpp"
#include "handshare/hiro/hiro_device.hpp"
#include "handshare/world/grasp.hpp"
#include "handshare/haptic/sim_hand.hpp"
#include "handshare/session/peer_contacts.hpp"

namespace handshare::haptic {

namespace {

std::unique_ptr<Device> MakeDevice(const HapticNodeConfig& c) {
  if (c.device == "sim") {
    // Each user's default motion happens at its own place, so several default hands do not
    // overlap: the place is derived from the user name.
    const double x = static_cast<double>(std::hash<std::string>{}(c.user) % 5) * 0.08 - 0.16;
    HandScript script = c.script.empty() ? HandScript::Default(Eigen::Vector3d(x, -0.05, 0.12))
                                         : HandScript::Load(c.script);
    return std::make_unique<SimDevice>(std::move(script));
  }
  if (c.device == "hiro") {
    hiro::HiroSimOptions sim;
    if (!c.script.empty()) sim.script = HandScript::Load(c.script);
    return hiro::MakeHiroDevice(c.hiro_config, sim);
  }
  if (c.device == "replay") return std::make_unique<ReplayDevice>(ReplayLog::Load(c.replay_file), c.replay_loop);
  throw std::invalid_argument("device '" + c.device + "' is not available (this build has: sim, hiro, replay)");
}

void Fill(msg::DeviceState& out, const HapticSnapshot& s) {
  out.stamp_ns(s.stamp_ns);
  out.seq(static_cast<std::uint32_t>(s.seq));
  for (int k = 0; k < 3; ++k) out.p_WH_m()[k] = s.p_WH_m[k];
  for (int k = 0; k < 4; ++k) out.q_WH_wxyz()[k] = s.q_WH_wxyz[k];
  for (int i = 0; i < kFingers; ++i) {
    for (int k = 0; k < 3; ++k) {
      out.p_WE_m()[i][k] = s.p_WE_m[i][k];
      out.f_E_W_N()[i][k] = s.f_E_W_N[i][k];
    }
  }
  out.fingertip_radius_m(s.fingertip_radius_m);
  out.fault(s.fault);
}

void FillStats(msg::LoopStatistics& out, const common::LoopStats& s, std::uint64_t faults) {
  out.rate_Hz(s.rate_Hz);
  out.jitter_p50_us(s.jitter.Quantile(0.5));
  out.jitter_p99_us(s.jitter.Quantile(0.99));
  out.jitter_max_us(s.jitter.max_us());
  out.step_p50_us(s.step.Quantile(0.5));
  out.step_p99_us(s.step.Quantile(0.99));
  out.steps(s.steps);
  out.overruns(s.overruns);
  out.resyncs(s.resyncs);
  out.faults(faults);
}


msg::ControlEventKind ToMessage(controls::EventKind k) {
  switch (k) {
    case controls::EventKind::kPressed: return msg::CONTROL_PRESSED;
    case controls::EventKind::kReleased: return msg::CONTROL_RELEASED;
    case controls::EventKind::kMoved: return msg::CONTROL_MOVED;
    case controls::EventKind::kPageTurned: return msg::CONTROL_PAGE_TURNED;
    case controls::EventKind::kMissed: return msg::CONTROL_MISSED;
    case controls::EventKind::kOpened: return msg::CONTROL_OPENED;
  }
  return msg::CONTROL_MISSED;
}

// The dynamic body this hand claims for simulating it: the one it grasps (world::IsGrasp on
// the forces on the body), else the one it touches with the largest force, or -1. The world
// server gives a claimed free body to its claimant; a body held by another stays theirs.
std::int32_t ClaimedBody(const ContactReport& r) {
  std::int32_t touched = -1;
  double strongest = 0.0;
  for (int b = 0; b < r.num_bodies; ++b) {
    world::FingerForce on_body[kFingers];
    for (int i = 0; i < kFingers; ++i) {
      const auto& f = r.fingers[i];
      on_body[i].active = f.active && f.object == r.bodies[b].object;
      for (int k = 0; k < 3; ++k) on_body[i].f_W_N[k] = f.f_W_N[k];
      const double norm = std::sqrt(f.f_W_N[0] * f.f_W_N[0] + f.f_W_N[1] * f.f_W_N[1] + f.f_W_N[2] * f.f_W_N[2]);
      if (on_body[i].active && (touched < 0 || norm > strongest)) {
        touched = r.bodies[b].object;
        strongest = norm;
      }
    }
    if (world::IsGrasp(on_body, kFingers)) return r.bodies[b].object;
  }
  return touched;
}

}  // namespace

HapticNode::HapticNode(HapticNodeConfig config) : config_(std::move(config)) {}

int HapticNode::Run() {
  using Clock = std::chrono::steady_clock;
  auto device = MakeDevice(config_);  // script errors surface before joining the session
  const std::string tag = "[haptic_node " + config_.user + "] ";
  auto say = [&](const std::string& line) {
    std::printf("%s%s\n", tag.c_str(), line.c_str());
    std::fflush(stdout);
  };

  std::ofstream trace;
  if (!config_.trace_file.empty()) {
    trace.open(config_.trace_file);
    if (!trace) throw std::runtime_error("cannot write trace file " + config_.trace_file);
    trace << std::setprecision(9);
    WriteTraceHeader(trace);
  }

  dds::Participant participant(config_.where.domain_id, config_.where.session, "haptic_node/" + config_.user,
                               config_.where.qos_file);
  dds::MemberAnnouncement member(participant, config_.user, msg::NODE_HAPTIC, device->name());
  auto state_writer = dds::MakeWriter<msg::DeviceState>(participant, dds::topics::kDeviceState);
  auto stats_writer = dds::MakeWriter<msg::LoopStatistics>(participant, dds::topics::kLoopStatistics);
  auto contact_writer = dds::MakeWriter<msg::ContactSet>(participant, dds::topics::kContactSet);
  auto event_writer = dds::MakeWriter<msg::ControlEvent>(participant, dds::topics::kControlEvent);
  auto scene_reader = dds::MakeReader<msg::SceneState>(participant, dds::topics::kSceneState);
  auto contact_reader = dds::MakeReader<msg::ContactSet>(participant, dds::topics::kContactSet);
  auto object_reader = dds::MakeReader<msg::ObjectState>(participant, dds::topics::kObjectState);

  HapticLoopConfig loop_config{config_.rate_Hz, true};
  HapticLoop loop(*device, loop_config);
  const bool realtime = loop.Start();
  say("joined session '" + config_.where.session + "' on domain " + std::to_string(config_.where.domain_id) +
      ": device " + device->name() + ", loop " + std::to_string(static_cast<int>(config_.rate_Hz)) + " Hz" +
      (realtime ? " (SCHED_FIFO)" : " (normal priority: no permission for SCHED_FIFO)"));

  msg::DeviceState state;
  state.user(config_.user);
  state.session(config_.where.session);
  msg::LoopStatistics stats_msg;
  stats_msg.node("haptic_node/" + config_.user);
  stats_msg.session(config_.where.session);
  msg::ContactSet contacts;
  contacts.user(config_.user);
  contacts.session(config_.where.session);

  world::SceneWorldOptions models;
  models.cache_dir = config_.cache_dir.empty() ? world::DefaultCacheDir() : std::filesystem::path(config_.cache_dir);
  models.fingertip_radius_m = device->capabilities().fingertip_radius_m;
  models.max_force_N = device->capabilities().max_fingertip_force_N;
  std::shared_ptr<SceneRenderer> renderer;
  std::uint32_t scene_revision = 0;
  ContactReport report;
  bool have_report = false, last_sent_active = false;
  // The other users' newest contact sets (a vanished peer's fade out within 0.5 s).
  session::PeerContacts peers;
  // Published states of rigid bodies (object id -> newest): followed unless this user owns it.
  struct ReceivedState {
    msg::ObjectState state;
    std::uint64_t received_ns = 0;  // when it arrived (this host's steady clock)
  };
  std::map<std::string, ReceivedState> body_states;

  const auto start = Clock::now();
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / config_.publish_Hz));
  auto next = start;
  auto next_stats = start + std::chrono::seconds(1);
  HapticSnapshot snapshot;
  common::LoopStats stats;
  std::uint64_t published = 0, events_sent = 0;
  msg::SceneState scene_msg;
  msg::ContactSet peer;
  dds::SampleMeta meta;
  while (!common::ShutdownRequested()) {
    if (config_.where.duration.count() > 0 && Clock::now() - start >= config_.where.duration) break;

    // The scene: a new revision (another world, or the same world with new gravity) gets new
    // models; dynamic bodies keep their poses when the world stays the same.
    while (scene_reader.TakeNext(scene_msg, meta)) {
      if (!meta.valid_data || scene_msg.revision() == scene_revision) continue;
      scene_revision = scene_msg.revision();
      try {
        scene::Scene scene = scene::LoadSceneByName(scene_msg.scene().to_string());
        const auto& g = scene_msg.gravity_W_m_per_s2();
        scene.gravity_W_m_per_s2 = Eigen::Vector3d(g[0], g[1], g[2]);
        const auto t0 = Clock::now();
        auto next_renderer = std::make_shared<SceneRenderer>(scene, models);
        if (renderer && have_report && renderer->scene().name == scene.name) {
          for (int b = 0; b < report.num_bodies; ++b) {
            const auto& body = report.bodies[b];
            Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
            X.linear() = Eigen::Quaterniond(body.q_WO_wxyz[0], body.q_WO_wxyz[1], body.q_WO_wxyz[2],
                                            body.q_WO_wxyz[3]).normalized().toRotationMatrix();
            X.translation() = Eigen::Vector3d(body.p_WO_m[0], body.p_WO_m[1], body.p_WO_m[2]);
            next_renderer->PlaceBody(renderer->IdOf(body.object), X);
            char line[160];
            std::snprintf(line, sizeof line, "  %s stays at (%.3f, %.3f, %.3f) m", renderer->IdOf(body.object).c_str(),
                          X.translation().x(), X.translation().y(), X.translation().z());
            say(line);
          }
        }
        if (!renderer || renderer->scene().name != scene.name) body_states.clear();
        peers.Clear();
        renderer = next_renderer;
        have_report = false;
        loop.SetRenderer(renderer);
        if (const double t_s = loop.now_s(); device->OnWorldReady(t_s, scene.name)) {
          char started[120];
          std::snprintf(started, sizeof started, "hand script starts at loop time %.3f s (the first world is here)",
                        t_s);
          say(started);
        }
        char line[160];
        std::snprintf(line, sizeof line, "scene '%s' revision %u: %d objects, %zu controls, gravity %.2f m/s^2 (%.2f s)",
                      scene.name.c_str(), scene_revision, renderer->models().world->num_objects(),
                      scene.controls.size(), scene.gravity_W_m_per_s2.z(),
                      std::chrono::duration<double>(Clock::now() - t0).count());
        say(line);
      } catch (const std::exception& e) {
        // A scene this node cannot build: keep the old one (or none): no forces from it.
        say(std::string("cannot build scene '") + scene_msg.scene().to_string() + "': " + e.what());
      }
    }
    loop.CollectRetired();

    if (renderer) {
      // Control events: to the world server, reliably.
      controls::ControlEvent event;
      while (renderer->TakeEvent(event)) {
        msg::ControlEvent m;
        m.session(config_.where.session);
        m.user(config_.user);
        m.control_id(std::string(event.id()));
        m.kind(ToMessage(event.kind));
        m.value(event.value);
        m.index(event.index);
        m.error_m(event.error_m);
        m.stamp_ns(common::SteadyNowNs());
        event_writer.Write(m);
        ++events_sent;
        char line[160];
        std::snprintf(line, sizeof line, "control %s: %s (value %.3f, error %.1f mm)", std::string(event.id()).c_str(),
                      controls::ToString(event.kind), event.value, 1e3 * event.error_m);
        say(line);
      }
      if (renderer->TakeReport(report)) have_report = true;

      // The other users' contacts on this world's objects, for the shared deformables.
      // A peer touching something sends its contact set at its publish rate; one silent for
      // longer has gone (or stopped touching without a last sample): its contacts fade out.
      const auto now = Clock::now();
      while (contact_reader.TakeNext(peer, meta)) {
        if (meta.valid_data) peers.Receive(peer, now, config_.user);
      }
      peers.Expire(now);
      RemoteContacts remote;
      peers.ForEach(renderer->models(), now, [&](const session::PeerContact& c, const msg::ContactSet&) {
        // Shared solves are for deformables (the objects with a contact solver); rigid bodies
        // move by their owner's published pose instead.
        if (remote.count >= kMaxRemoteContacts || renderer->models().world->contact_solver(c.object) == nullptr) return;
        remote.items[remote.count++] = c;
      });
      renderer->SetRemote(remote);

      // Rigid bodies: the owner simulates a grasped body, the world server a free one; this
      // hand follows every body it does not own itself.
      msg::ObjectState body;
      while (object_reader.TakeNext(body, meta)) {
        if (!meta.valid_data || body.session().to_string() != config_.where.session) continue;
        body_states[body.object_id().to_string()] = {body, common::SteadyNowNs()};
      }
      FollowedBodies followed;
      for (const auto& [id, received] : body_states) {
        const msg::ObjectState& st = received.state;
        if (st.owner().to_string() == config_.user || followed.count >= kMaxReportedBodies) continue;
        const auto object = renderer->models().Find(id);
        if (object < 0 || std::find(renderer->models().dynamic_bodies.begin(), renderer->models().dynamic_bodies.end(),
                                    object) == renderer->models().dynamic_bodies.end()) {
          continue;
        }
        auto& item = followed.items[followed.count++];
        item.object = object;
        for (int k = 0; k < 3; ++k) item.p_WO_m[k] = st.p_WO_m()[k];
        for (int k = 0; k < 4; ++k) item.q_WO_wxyz[k] = st.q_WO_wxyz()[k];
        for (int k = 0; k < 3; ++k) item.v_WO_m_per_s[k] = st.v_WO_m_per_s()[k];
        item.received_ns = received.received_ns;
      }
      renderer->SetFollowed(followed);
    }

    if (loop.TakeSnapshot(snapshot)) {
      Fill(state, snapshot);
      // Skip what nobody needs: no viewer matched, nothing sent (the trace still records).
      if (state_writer.matched_readers() > 0) {
        state_writer.Write(state);
        ++published;
      }
      if (trace) WriteTraceRow(trace, snapshot);
    }
    // Contact set: while touching, and once more when the last contact ends.
    if (renderer && have_report) {
      bool active = false;
      for (int i = 0; i < kFingers; ++i) {
        const auto& f = report.fingers[i];
        auto& m = contacts.fingers()[i];
        m.active(f.active);
        active |= f.active;
        m.object_id(f.active ? renderer->IdOf(f.object) : std::string());
        m.surface_node(f.node);
        for (int k = 0; k < 3; ++k) {
          m.p_W_m()[k] = f.p_WC_m[k];
          m.n_W()[k] = f.n_W[k];
          m.p_WE_m()[k] = f.p_WE_m[k];
          m.u_imposed_W_m()[k] = f.u_W_m[k];
          m.f_W_N()[k] = f.f_W_N[k];
        }
        m.radius_m(models.fingertip_radius_m);
        m.depth_m(f.depth_m);
      }
      const std::int32_t grasped = ClaimedBody(report);
      contacts.grasped_object_id(grasped >= 0 ? renderer->IdOf(grasped) : std::string());
      // The body this node simulates for the session: the one the world server gave it.
      std::int32_t owned = -1;
      for (const auto& [id, received] : body_states) {
        if (received.state.owner().to_string() == config_.user) owned = renderer->models().Find(id);
      }
      contacts.simulating(false);
      contacts.simulated_object_id("");
      for (int b = 0; b < report.num_bodies; ++b) {
        if (owned < 0 || report.bodies[b].object != owned) continue;
        contacts.simulating(true);
        contacts.simulated_object_id(renderer->IdOf(owned));
        for (int k = 0; k < 3; ++k) {
          contacts.p_WO_m()[k] = report.bodies[b].p_WO_m[k];
          contacts.v_WO_m_per_s()[k] = report.bodies[b].v_WO_m_per_s[k];
        }
        for (int k = 0; k < 4; ++k) contacts.q_WO_wxyz()[k] = report.bodies[b].q_WO_wxyz[k];
      }
      // An owner keeps reporting its body's pose after letting go, until the server frees it.
      active |= contacts.simulating() || grasped >= 0;
      if ((active || last_sent_active) && contact_writer.matched_readers() > 0) {
        contacts.stamp_ns(common::SteadyNowNs());
        contacts.seq(contacts.seq() + 1);
        contact_writer.Write(contacts);
      }
      last_sent_active = active;
    }
    if (Clock::now() >= next_stats) {
      next_stats += std::chrono::seconds(1);
      if (loop.TakeStats(stats) && stats_writer.matched_readers() > 0) {
        FillStats(stats_msg, stats, loop.faults());
        stats_writer.Write(stats_msg);
      }
    }
    next += period;
    if (Clock::now() > next + 5 * period) next = Clock::now();
    std::this_thread::sleep_until(next);
  }
  loop.Stop();
  loop.TakeStats(stats);
  std::printf("[haptic_node %s] loop statistics: rate %.1f Hz, steps %llu, jitter p50 %.0f us "
              "p99 %.0f us max %.0f us, step p50 %.1f us p99 %.1f us, overruns %llu, resyncs %llu, "
              "faults %llu, device states published %llu, control events %llu\n",
              config_.user.c_str(), stats.rate_Hz, static_cast<unsigned long long>(stats.steps),
              stats.jitter.Quantile(0.5), stats.jitter.Quantile(0.99), stats.jitter.max_us(),
              stats.step.Quantile(0.5), stats.step.Quantile(0.99), static_cast<unsigned long long>(stats.overruns),
              static_cast<unsigned long long>(stats.resyncs),
              static_cast<unsigned long long>(loop.faults()),
              static_cast<unsigned long long>(published), static_cast<unsigned long long>(events_sent));
  std::fflush(stdout);
  return 0;
}

}  // namespace handshare::haptic
