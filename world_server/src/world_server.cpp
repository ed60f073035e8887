#include "handshare/world_server/world_server.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <sstream>
#include <thread>

#include "handshare/common/clock.hpp"
#include "handshare/common/latency_histogram.hpp"
#include "handshare/common/overload_watch.hpp"
#include "handshare/common/shutdown.hpp"
#include "handshare/dds/loop_traffic.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/dds/pass_statistics.hpp"
#include "handshare/node/node_main.hpp"
#include "handshare/scene/scene.hpp"
#include "console_log.hpp"
#include "pose_trace.hpp"
#include "sample_intake.hpp"
#include "server_session.hpp"
#include "session_log_writer.hpp"
#include "session_publisher.hpp"

namespace handshare::server {

namespace {

// The tick's loop statistics' node: program/name like every station's ("graphics_node/screen"),
// the world server's one loop being its tick.
constexpr const char* kTickStationNode = "world_server/tick";

ServerSessionConfig SessionConfig(const WorldServerConfig& config) {
  ServerSessionConfig c;
  c.session = config.where.session;
  c.domain_id = config.where.domain_id;
  c.tick_Hz = config.tick_Hz;
  if (!config.cache_dir.empty()) c.objects.models.cache_dir = config.cache_dir;
  c.objects.dump_dir = config.dump_dir;
  c.objects.delta.threshold_m = config.deformation_threshold_m;
  c.visit_turn = std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::duration<double, std::ratio<60>>(config.visit_minutes));
  c.tour_start = config.scene;
  return c;
}

std::string HostName() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "";
  return name;
}

}  // namespace

void DeclareWorldServerOptions(common::Options& options) {
  options.Value("scene", "NAME", "scene to start with (assets/scenes/NAME.json)", "start_menu")
      .Value("log", "FILE", "record the session in this SQLite session log (a new session is appended; "
                            "read it with session_report)", "")
      .Value("cache", "DIR", "deformable models' cache (default: $HANDSHARE_CACHE, else ~/.cache/handshare)", "")
      .Value("dump-deformation", "DIR", "write the loads and field of every published deformation to DIR "
                                        "(for an independent FEM check)", "")
      .Value("pose-trace", "FILE", "write every published rigid-body state to a CSV file (stamp_ns on the host's "
                                   "steady clock, object_id, owner, position, velocity)", "")
      .Value("deformation-threshold", "M", "re-send a deformed surface node when it moved more than M metres", "1e-4")
      .Value("resume-within", "SEC", "with --log: a session of this name whose server was killed less than SEC "
                                     "ago is resumed where it was (0: always start afresh)", "600")
      .Value("visit-minutes", "M", "a visitor's turn (a haptic member's, from its join) ends M minutes later: the "
                                   "board says so and --log records it (fractions allowed; 0: turns never end; "
                                   "the paper's 10 by default)", "10");
}

WorldServerConfig ReadWorldServerOptions(const common::Options& o) {
  WorldServerConfig config;
  config.where = node::ReadSessionOptions(o);
  config.scene = o.GetString("scene");
  config.log_file = o.GetString("log");
  config.cache_dir = o.GetString("cache");
  config.dump_dir = o.GetString("dump-deformation");
  config.pose_trace_file = o.GetString("pose-trace");
  config.deformation_threshold_m = o.GetDouble("deformation-threshold", 1e-9, 0.01);
  config.resume_within_s = o.GetDouble("resume-within", 0.0, 1e9);
  config.visit_minutes = o.GetDouble("visit-minutes", 0.0, 24.0 * 60.0);  // up to a day
  return config;
}

WorldServer::WorldServer(WorldServerConfig config)
    : config_(std::move(config)), start_(std::chrono::steady_clock::now()) {}

WorldServer::~WorldServer() = default;

void WorldServer::Say(const std::string& line) {
  const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::printf("[world_server %8.3f s] %s\n", t, line.c_str());
  std::fflush(stdout);
}

bool WorldServer::CheckLog() {
  if (!log_ || log_failed_) return !log_failed_;
  if (const std::string error = log_->error(); !error.empty()) {
    log_failed_ = true;
    Say("session log failed, the session goes on without it: " + error);
  }
  return !log_failed_;
}

int WorldServer::Run() {
  using Clock = std::chrono::steady_clock;
  start_ = Clock::now();
  scene::Scene scene = scene::LoadSceneByName(config_.scene);
  // A session whose server was killed goes on where its log says it was (read before this
  // run's own session row exists).
  std::optional<ResumePoint> resume;
  if (!config_.log_file.empty() && config_.resume_within_s > 0.0) {
    resume = FindResumePoint(config_.log_file, config_.where.session, common::UnixNowNs(),
                             static_cast<std::uint64_t>(config_.resume_within_s * 1e9));
  }
  // The log opens once the scene is known to load (a bad scene name leaves no empty session
  // behind) and before any DDS entity exists (a bad log file keeps us out of the session).
  if (!config_.log_file.empty() && !log_) {
    log_ = std::make_unique<SessionLog>(
        config_.log_file, SessionStart{config_.where.session, config_.where.domain_id, HostName(),
                                       static_cast<std::int64_t>(getpid()), common::UnixNowNs(),
                                       resume ? resume->session_id : 0});
  }
  std::optional<PoseTrace> pose_trace;
  if (!config_.pose_trace_file.empty()) {
    pose_trace_file_.open(config_.pose_trace_file);
    if (!pose_trace_file_) throw std::runtime_error("cannot write the pose trace " + config_.pose_trace_file);
    pose_trace.emplace(pose_trace_file_);
  }
  dds::Participant participant(config_.where, "world_server");
  if (log_) Say("session log " + log_->file().string() + ": session #" + std::to_string(log_->session_id()));
  if (resume) {
    Say("resuming session #" + std::to_string(resume->session_id) + ", whose server was lost " +
        std::to_string((common::UnixNowNs() - std::min(common::UnixNowNs(), resume->last_seen_unix_ns)) / 1000000) +
        " ms ago: world '" + resume->state.scene + "' revision " + std::to_string(resume->state.revision) + ", " +
        std::to_string(resume->poses.size()) + " body poses, board message #" +
        std::to_string(resume->state.message_id) + ", " + std::to_string(resume->controls.size()) + " control places");
  }
  // The tick's consumers, in the order they take each tick's events: the samples are written,
  // and the log's rows queued (a checkpoint committed), before the console prints the lines
  // that say so.
  SessionPublisher publisher(participant, config_.where.session);
  SampleIntake intake(participant, config_.where.session);
  std::optional<SessionLogWriter> log_writer;
  if (log_) log_writer.emplace(*log_);
  ConsoleLog console([this](const std::string& line) { Say(line); });
  std::vector<SessionEventSink*> sinks{&publisher};
  if (log_writer) sinks.push_back(&*log_writer);
  if (pose_trace) sinks.push_back(&*pose_trace);
  sinks.push_back(&console);
  const auto deliver = [&](const ServerSession::Events& events, Clock::time_point now) {
    for (SessionEventSink* sink : sinks) sink->Take(events, now);
  };

  // The tick as a station (LoopStatistics, once a second, like a screen's frames): the operator's
  // page shows it, and the world server's own reader takes it into the session log like any
  // station's. An older keystore that does not grant it only loses these statistics.
  auto stats_writer = dds::MakeWriterIfGranted<msg::LoopStatistics>(
      participant, dds::topics::kLoopStatistics, [this](const std::string& line) { Say(line); },
      "the operator's page shows no statistics of the tick");
  dds::LoopTraffic stats_traffic(participant);
  msg::LoopStatistics stats;
  stats.node(kTickStationNode);
  stats.session(config_.where.session);

  ServerSession session(SessionConfig(config_), std::move(scene), resume ? &*resume : nullptr);
  deliver(session.Start(), Clock::now());
  TickInputs inputs;

  // One tick per period at absolute deadlines, re-synced after a stall.
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / config_.tick_Hz));
  auto next = Clock::now();
  Clock::time_point last_tick{};
  dds::PassStatistics tick_stats(period, next);  // the station's: per second, ticks due at `next`
  auto last_stats = next;
  // Once a second: the ticks' rate, lateness (jitter: begun after due) and work (step), overruns
  // (a tick begun a whole period late), the samples the session's checks refused, and the
  // participant's deadline misses and bytes written. The period restarts whether or not a reader
  // listens.
  const auto publish_tick_statistics = [&](Clock::time_point now) {
    tick_stats.Fill(stats, now);
    stats.samples_dropped(session.dropped().total());
    stats_traffic.Fill(stats, now);
    if (stats_writer && stats_writer.matched_readers() > 0) stats_writer.Write(stats);
  };
  common::LatencyHistogram tick_work;      // one tick's stages, start to end
  common::LatencyHistogram tick_interval;  // one tick's start to the next's (period 1 / tick_Hz)
  // Below half its rate or a 100 ms stall: said in the log (the issue's bar: tick p99 <= 100 ms).
  common::OverloadWatch overload("the world server's tick", {config_.tick_Hz, 0.5 * config_.tick_Hz});
  while (!common::ShutdownRequested()) {
    if (config_.where.duration.count() > 0 && Clock::now() - start_ >= config_.where.duration) break;
    const auto now = Clock::now();
    const double dt_s = last_tick == Clock::time_point{} ? 1.0 / config_.tick_Hz
                                                         : std::chrono::duration<double>(now - last_tick).count();
    if (last_tick != Clock::time_point{}) tick_interval.Record(1e6 * dt_s);
    last_tick = now;
    if (std::string line = overload.Tick(static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(now.time_since_epoch()).count())); !line.empty()) Say(line);
    intake.Take(inputs);
    deliver(session.Tick(inputs, now, std::min(dt_s, 0.1)), now);
    CheckLog();
    const auto ended = Clock::now();
    tick_work.Record(std::chrono::duration<double, std::micro>(ended - now).count());
    tick_stats.Record(next, now, ended);
    if (ended - last_stats >= std::chrono::seconds(1)) {
      publish_tick_statistics(ended);
      last_stats = ended;
    }
    next += period;
    if (Clock::now() > next + 5 * period) {
      next = Clock::now();
      stats.resyncs(stats.resyncs() + 1);
    }
    std::this_thread::sleep_until(next);
  }
  Say("shutting down: " + std::to_string(session.members().joined_total()) + " members joined, " +
      std::to_string(session.members().present().size()) + " still present, " +
      std::to_string(publisher.deformations_sent()) + " deformation samples sent, samples dropped: " +
      session.dropped().Summary());
  char line[320];
  std::snprintf(line, sizeof line,
                "ticks: %llu at %.0f Hz, work p50 %.0f us p99 %.0f us max %.0f us, interval p99 %.1f ms max %.1f ms; %s",
                static_cast<unsigned long long>(tick_work.count()), config_.tick_Hz, tick_work.Quantile(0.5),
                tick_work.Quantile(0.99), tick_work.max_us(), 1e-3 * tick_interval.Quantile(0.99),
                1e-3 * tick_interval.max_us(), overload.Summary().c_str());
  Say(line);
  Say(participant.TrafficSummary());
  CloseLog();
  return log_failed_ ? 1 : 0;
}

void WorldServer::CloseLog() {
  if (!log_) return;
  // Members still present stay open in the log: the report shows them "present at end".
  log_->End(common::UnixNowNs());
  try {
    log_->Flush();
    if (!log_failed_) Say("session log: session #" + std::to_string(log_->session_id()) + " written");
  } catch (const SessionLogError& e) {
    if (!log_failed_) Say(std::string("session log failed: ") + e.what());
    log_failed_ = true;
  }
  if (log_->dropped_rows() > 0) Say("session log: " + std::to_string(log_->dropped_rows()) + " rows dropped");
}

}  // namespace handshare::server
