#include "handshare/haptic/haptic_node.hpp"

#include <cstdio>
#include <fstream>
#include <functional>
#include <iomanip>
#include <memory>
#include <stdexcept>
#include <thread>

#include "handshare/common/shutdown.hpp"
#include "handshare/dds/membership.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/haptic/haptic_loop.hpp"
#include "handshare/haptic/replay.hpp"
#include "handshare/haptic/sim_hand.hpp"

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
  if (c.device == "replay") return std::make_unique<ReplayDevice>(ReplayLog::Load(c.replay_file), c.replay_loop);
  throw std::invalid_argument("device '" + c.device + "' is not available (this build has: sim, replay)");
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

}  // namespace

HapticNode::HapticNode(HapticNodeConfig config) : config_(std::move(config)) {}

int HapticNode::Run() {
  using Clock = std::chrono::steady_clock;
  auto device = MakeDevice(config_);  // script errors surface before joining the session

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

  HapticLoop loop(*device, HapticLoopConfig{config_.rate_Hz, true});
  const bool realtime = loop.Start();
  std::printf("[haptic_node %s] joined session '%s' on domain %d: device %s, loop %.0f Hz%s\n",
              config_.user.c_str(), config_.where.session.c_str(), config_.where.domain_id, device->name(),
              config_.rate_Hz, realtime ? " (SCHED_FIFO)" : " (normal priority: no permission for SCHED_FIFO)");
  std::fflush(stdout);

  msg::DeviceState state;
  state.user(config_.user);
  state.session(config_.where.session);
  msg::LoopStatistics stats_msg;
  stats_msg.node("haptic_node/" + config_.user);
  stats_msg.session(config_.where.session);

  const auto start = Clock::now();
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / config_.publish_Hz));
  auto next = start;
  auto next_stats = start + std::chrono::seconds(1);
  HapticSnapshot snapshot;
  common::LoopStats stats;
  std::uint64_t published = 0;
  while (!common::ShutdownRequested()) {
    if (config_.where.duration.count() > 0 && Clock::now() - start >= config_.where.duration) break;
    if (loop.TakeSnapshot(snapshot)) {
      Fill(state, snapshot);
      // Skip what nobody needs: no viewer matched, nothing sent (the trace still records).
      if (state_writer.matched_readers() > 0) {
        state_writer.Write(state);
        ++published;
      }
      if (trace) WriteTraceRow(trace, snapshot);
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
              "p99 %.0f us max %.0f us, step p99 %.1f us, overruns %llu, resyncs %llu, faults %llu, "
              "device states published %llu\n",
              config_.user.c_str(), stats.rate_Hz, static_cast<unsigned long long>(stats.steps),
              stats.jitter.Quantile(0.5), stats.jitter.Quantile(0.99), stats.jitter.max_us(),
              stats.step.Quantile(0.99), static_cast<unsigned long long>(stats.overruns),
              static_cast<unsigned long long>(stats.resyncs),
              static_cast<unsigned long long>(loop.faults()),
              static_cast<unsigned long long>(published));
  std::fflush(stdout);
  return 0;
}

}  // namespace handshare::haptic
