#include "handshare/haptic/haptic_node.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iomanip>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "bridge_conversions.hpp"
#include "desk_device.hpp"
#include "haptic_bridge.hpp"
#include "handshare/node/rejoin_clock.hpp"
#include "handshare/common/shutdown.hpp"
#include "handshare/dds/membership.hpp"
#include "handshare/haptic/haptic_loop.hpp"
#include "handshare/haptic/plugin_device.hpp"
#include "handshare/haptic/replay.hpp"
#include "handshare/haptic/sim_hand.hpp"
#include "handshare/hiro/hiro_device.hpp"

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
  // A person at the view's mouse and keyboard: the bridge hands it their input (DeskInput).
  if (c.device == "desk") return std::make_unique<DeskDevice>();
  if (c.device.rfind("plugin:", 0) == 0) {
    PluginDeviceOptions o = PluginDeviceOptions::FromSpec(c.device);
    o.origin_W = Eigen::Vector3d(c.device_origin_m[0], c.device_origin_m[1], c.device_origin_m[2]);
    o.scale = c.device_scale;
    o.deadline_s = c.device_deadline_s;
    return PluginDevice::Open(o);
  }
  throw std::invalid_argument("device '" + c.device + "' is not available (this build has: sim, hiro, replay, desk, plugin:PATH.so[:ARGS])");
}

/// Everything of this node that lives on DDS: its participant, its member announcement and the
/// bridge's writers and readers. A rejoin makes a new one while the haptic loop runs on.
struct SessionLink {
  SessionLink(const HapticNodeConfig& config, Device& device, HapticLoop& loop, std::ostream* trace,
              HapticBridge::Say say)
      : participant(config.where, "haptic_node/" + config.user),
        member(participant, config.user, msg::NODE_HAPTIC, device.name(), 0.0, ToDeviceCaps(device.capabilities())),
        bridge(config, device, loop, participant, trace, std::move(say)) {}
  dds::Participant participant;
  dds::MemberAnnouncement member;
  HapticBridge bridge;
};

void PrintLoopSummary(const std::string& user, const common::LoopStats& stats, std::uint64_t faults,
                      const std::string& fault_causes, std::uint64_t rate_limited_steps, const HapticBridge& bridge) {
  std::printf("[haptic_node %s] loop statistics: rate %.1f Hz, steps %llu, jitter p50 %.0f us "
              "p99 %.0f us max %.0f us, step p50 %.1f us p99 %.1f us, overruns %llu, resyncs %llu, "
              "faults %llu, rate-limited steps %llu, device states published %llu, control events %llu, samples dropped %s\n",
              user.c_str(), stats.rate_Hz, static_cast<unsigned long long>(stats.steps), stats.jitter.Quantile(0.5),
              stats.jitter.Quantile(0.99), stats.jitter.max_us(), stats.step.Quantile(0.5), stats.step.Quantile(0.99),
              static_cast<unsigned long long>(stats.overruns), static_cast<unsigned long long>(stats.resyncs),
              static_cast<unsigned long long>(faults), static_cast<unsigned long long>(rate_limited_steps),
              static_cast<unsigned long long>(bridge.device_states_published()),
              static_cast<unsigned long long>(bridge.control_events_sent()), bridge.dropped().Summary().c_str());
  if (faults > 0) {
    std::printf("[haptic_node %s] faulted steps by cause: %s\n", user.c_str(), fault_causes.c_str());
  }
  if (const auto& age = bridge.peer_contact_age(); age.count() > 0) {
    std::printf("[haptic_node %s] peer contact sets: %llu taken, age at the bridge (sender's write to take, "
                "same host) p50 %.0f us p99 %.0f us max %.0f us\n",
                user.c_str(), static_cast<unsigned long long>(age.count()), age.Quantile(0.5), age.Quantile(0.99),
                age.max_us());
  }
  if (const auto& age = bridge.contact_report_age(); age.count() > 0) {
    std::printf("[haptic_node %s] contact sets: %llu written, age of the haptic step's report at the write "
                "p50 %.0f us p99 %.0f us max %.0f us\n",
                user.c_str(), static_cast<unsigned long long>(age.count()), age.Quantile(0.5), age.Quantile(0.99),
                age.max_us());
  }
  if (const auto& d = bridge.deadband(); d.offered() > 0) {
    // One line a test or a bench can read: how much of the peer stream the deadband saved.
    std::string why;
    for (int r = static_cast<int>(session::DeadbandReason::kOff); r < session::kDeadbandReasons; ++r) {
      const auto reason = static_cast<session::DeadbandReason>(r);
      if (d.sent_for(reason) > 0) why += std::string(" ") + session::ToString(reason) + " " + std::to_string(d.sent_for(reason));
    }
    std::printf("[haptic_node %s] contact deadband: weber %.2f, offered %llu, sent %llu, reduction %.1f %% (sent for:%s)\n",
                user.c_str(), d.config().weber, static_cast<unsigned long long>(d.offered()),
                static_cast<unsigned long long>(d.sent()), 100.0 * d.reduction(), why.c_str());
  }
  if (const auto c = bridge.coupling_stats(); c.channels_total > 0) {
    // The network coupling's passivity (contact/coupling_passivity.hpp): one line a test reads.
    std::printf("[haptic_node %s] coupling passivity: %s, channels %llu, steps %llu, held back %llu, "
                "energy sent %.6f J, received %.6f J, observer min %.3e J, drift max %.3f mm, "
                "granted at rest %.3e J in %llu steps\n",
                user.c_str(), bridge.coupling_passivity() ? "on" : "off",
                static_cast<unsigned long long>(c.channels_total), static_cast<unsigned long long>(c.steps),
                static_cast<unsigned long long>(c.held_back),
                c.energy_sent_J, c.energy_received_J, c.observer_min_J, 1e3 * c.drift_max_m,
                c.energy_granted_J, static_cast<unsigned long long>(c.granted_still));
  }
  if (const auto& age = bridge.peer_contact_loop_age(); age.count() > 0) {
    std::printf("[haptic_node %s] peer contact sets: %llu used, age at the haptic loop (sender's write to the "
                "first step using it, same host) p50 %.0f us p99 %.0f us max %.0f us\n",
                user.c_str(), static_cast<unsigned long long>(age.count()), age.Quantile(0.5), age.Quantile(0.99),
                age.max_us());
  }
  std::fflush(stdout);
}

void PrintBridgeSummary(const HapticNodeConfig& config, const HapticBridge& bridge) {
  // The bridge's own rate (does it hold its period under load?) and what it sent.
  const auto& interval = bridge.tick_interval();
  const double seconds = 1e-6 * interval.mean_us() * static_cast<double>(interval.count());
  std::printf("[haptic_node %s] bridge: %llu ticks, %.1f Hz of %.0f, interval p50 %.2f ms p99 %.2f ms max %.2f ms; "
              "streams %s: device states %llu, contact sets %llu (%llu at the full rate: a peer on the same object); "
              "device states sent as the hand moved %llu; %s\n",
              config.user.c_str(), static_cast<unsigned long long>(bridge.ticks()),
              seconds > 0.0 ? static_cast<double>(interval.count()) / seconds : 0.0, config.publish_Hz,
              1e-3 * interval.Quantile(0.5), 1e-3 * interval.Quantile(0.99), 1e-3 * interval.max_us(),
              config.paced_streams ? "paced" : "full", static_cast<unsigned long long>(bridge.device_states_published()),
              static_cast<unsigned long long>(bridge.contact_sets_sent()),
              static_cast<unsigned long long>(bridge.contact_sets_shared()),
              static_cast<unsigned long long>(bridge.device_states_on_motion()), bridge.overload().Summary().c_str());
  if (config.device == "desk") {
    std::printf("[haptic_node %s] desk: %llu inputs taken from the view\n", config.user.c_str(),
                static_cast<unsigned long long>(bridge.desk_inputs()));
  }
  std::fflush(stdout);
}

}  // namespace

HapticNode::HapticNode(HapticNodeConfig config) : config_(std::move(config)) {}

int HapticNode::Run() {
  using Clock = std::chrono::steady_clock;
  auto device = MakeDevice(config_);  // script errors surface before joining the session
  const std::string tag = "[haptic_node " + config_.user + "] ";
  auto say = [tag](const std::string& line) {
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

  const auto* plugin = dynamic_cast<const PluginDevice*>(device.get());
  if (plugin != nullptr) say("device " + plugin->Describe());
  HapticLoop loop(*device, HapticLoopConfig{config_.rate_Hz, true});
  auto link = std::make_unique<SessionLink>(config_, *device, loop, trace.is_open() ? &trace : nullptr, say);
  const bool realtime = loop.Start();
  say("joined session '" + config_.where.session + "' on domain " + std::to_string(config_.where.domain_id) +
      ": device " + device->name() + ", loop " + std::to_string(static_cast<int>(config_.rate_Hz)) + " Hz" +
      (realtime ? " (SCHED_FIFO)" : " (normal priority: no permission for SCHED_FIFO)"));

  // The bridge thread: one tick per period at absolute deadlines, re-synced after a stall;
  // between ticks it sleeps on its wake-up and runs the coupling stages whenever the haptic
  // step or a reader posts it (a contact set or an object state goes through at once). With
  // nothing to carry at the tick's rate the period is the bridge's idle one (TickPeriod); what
  // makes it busy again (a touch, a peer's set) or asks for a tick (a new world, a control's
  // state) brings the next tick forward.
  const auto start = Clock::now();
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / config_.publish_Hz));
  node::RejoinClock rejoin(std::chrono::duration<double>(config_.rejoin_after_s));
  auto next = start;
  while (!common::ShutdownRequested()) {
    if (config_.where.duration.count() > 0 && Clock::now() - start >= config_.where.duration) break;
    link->bridge.Tick();
    if (rejoin.Due(link->bridge.heard_world_server())) {
      // The haptic loop runs on meanwhile.
      say(rejoin.Message("world"));
      say(rejoin.Swap(link, [&] {
        return std::make_unique<SessionLink>(config_, *device, loop, trace.is_open() ? &trace : nullptr, say);
      }));
    }
    const auto due = next;
    next += link->bridge.TickPeriod();
    if (Clock::now() > next + 5 * period) next = Clock::now();
    while (link->bridge.WaitForCoupling(next)) {
      link->bridge.Couple();
      next = std::min(next, link->bridge.TickAsked() ? Clock::now() : due + link->bridge.TickPeriod());
    }
  }
  loop.Stop();
  link->bridge.WriteCouplingTrace();
  common::LoopStats stats;
  loop.TakeStats(stats);
  PrintLoopSummary(config_.user, stats, loop.faults(), loop.FaultCauses(), loop.rate_limited_steps(), link->bridge);
  PrintBridgeSummary(config_, link->bridge);
  if (plugin != nullptr) {
    const PluginFaults f = plugin->faults();
    say("device faults: " + std::to_string(f.total()) + " (calls failed " + std::to_string(f.read_errors) +
        ", not finite " + std::to_string(f.not_finite) + ", jumps " + std::to_string(f.jumps) + ", overruns " +
        std::to_string(f.overruns) + ")");
  }
  if (rejoin.rejoins() > 0) say("rejoined the session " + std::to_string(rejoin.rejoins()) + " time(s)");
  say(link->participant.TrafficSummary());
  return 0;
}

}  // namespace handshare::haptic
