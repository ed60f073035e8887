// net_bench: one-way latency of a contact set (handshare/contact_set, ContactSet, the project's
// stream profiles and typed layer) from one process's writer to another's reader, over Fast DDS
// shared memory, UDP on loopback and UDP between two network namespaces on a bridge, with the
// split of where the time goes; and the path from one haptic node's haptic step to another's,
// through the haptic node's own code (HapticNode: HapticLoop, SceneRenderer, HapticBridge).
//
//   net_bench --csv [--count N] [--rate HZ] [--node-count N] [--domain D] [--transports LIST]
//             [--fifo PRIO] [--keep DIR] [--security KEYSTORE] [--node-coupling woken|polled]
//             [--node-weber W]
//     --domain D (default 160): the runs use D, D+1, ... (two per transport, each on a domain
//     of its own so none meets a participant an earlier run left in its lease).
//     --security KEYSTORE: both ends run over DDS-Security with the keystore's identities of
//     haptic users alice and bob (deploy/security/make_keystore.sh --session 'net_bench_*' DIR
//     alice bob); every measure is then printed with the suffix _secured.
//     --fifo PRIO: both ends' processes run SCHED_FIFO at PRIO (every thread, Fast DDS's receive
//     threads included: they inherit it), to show what scheduling does to the tail.
//     --node-coupling: woken (default) the nodes' bridges as built, woken by the haptic step and
//     the readers; polled: HapticNodeConfig::coupling_on_wake off, contact sets taken and sent
//     at the bridge's 100 Hz ticks only (the bridge before the coupling path was event-driven).
//     --node-weber W (default 0.02): the nodes' contact-set deadband (0: off).
//     prints transport,measure,p50_us,p99_us,max_us rows (and '#' comment lines with the load,
//     losses and what was skipped). transport: shm | udp | netns; measure:
//       contact_one_way      stamp before the writer's write() -> sample taken by the reader
//       serialize            CDR encoding of the sample (dds::Serialize, in the writer process)
//       deserialize          CDR decoding (dds::Deserialize)
//       write_call           the writer's write() call (serialization, history, send)
//       write_to_wake        write() returned -> the reader's WaitSet woke (transport, receive
//                            thread, notification; negative when the reader wakes first)
//       wake_to_taken        WaitSet woke -> take() returned (deserialization, copy)
//       node_path            two haptic nodes (alice and bob pressing one soft block, each its
//                            own process): the sender's haptic step that made a contact set ->
//                            the receiver's haptic step that first used it
//       node_sender_handoff  sender's haptic step -> its bridge calls write()
//       node_write_call      the sender bridge's write() call
//       node_dds_and_tick    write() called -> the receiver's bridge took the set (the DDS hop,
//                            the listener's wake-up; polled: the wait for the next bridge tick)
//       node_receiver_handoff receiver bridge took it -> its haptic step that first used it
//   Both directions are counted; the pairs are matched by the set's stamp (its write() call),
//   which the receiving bridge's trace keeps with the take and the first use.
//   One clock: CLOCK_MONOTONIC, shared by the processes of one host, network namespaces too.
//   The shm and udp transports are forced by a QoS file made from the project's
//   (deploy/qos/handshare_qos.xml, or $HANDSHARE_QOS_FILE) with the participant's builtin
//   transports replaced by one user transport. netns needs root and `ip` (iproute2): without
//   them its rows are skipped with a '#' line saying why.
//
//   net_bench --role writer|reader --qos FILE --domain D --session S --count N --rate HZ --out FILE
//   net_bench --role node --user alice|bob --assets DIR --qos FILE --domain D --session S
//             --node-count N --out FILE
//     one end (what --csv runs, in a namespace for netns).
#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "handshare/common/clock.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/dds/participant.hpp"
#include "handshare/dds/serialization.hpp"
#include "handshare/dds/topics.hpp"
#include "handshare/haptic/haptic_node.hpp"

extern char** environ;

namespace {

using namespace handshare;
namespace fs = std::filesystem;

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Options {
  bool csv = false;
  std::string role;
  std::string transport;
  std::string qos;
  std::string session;
  std::string out;
  std::string keep;
  std::vector<std::string> transports = {"shm", "udp", "netns"};
  int domain = 160;
  int fifo = 0;           // > 0: both ends run SCHED_FIFO at this priority (every thread)
  int count = 5000;       // samples measured in the contact_one_way run
  int node_count = 2000;  // node path: each haptic node runs NodeSeconds (about this many sets each way when polled)
  double rate_Hz = 1000.0;
  std::string security;   // a keystore: both ends run secured (DDS-Security), as haptic users alice and bob
  std::string user;       // --role node: alice or bob
  std::string assets;     // --role node: the scene and hand scripts (WriteNodeAssets)
  double node_weber = 0.02;             // the nodes' contact-set deadband in the node path
  std::string node_coupling = "woken";  // woken: the bridge as built; polled: at its 100 Hz ticks only (as before)
};

// How long each haptic node of the node path runs: its world's build, then about node_count
// sets each way at the polled bridge's 100 Hz (more when woken).
double NodeSeconds(const Options& o) { return 6.0 + static_cast<double>(o.node_count) / 100.0; }

// Secured runs print their measures with this suffix ("contact_one_way_secured"), so one CSV can
// hold rows with and without security.
std::string Secured(const Options& o) { return o.security.empty() ? "" : "_secured"; }
// The ends' participant names: a secured run needs identities of the keystore (haptic users
// alice and bob: the writer writes contact sets, the reader reads them, as two haptic nodes).
std::string EndName(const Options& o, const char* plain, const char* user) {
  return o.security.empty() ? std::string(plain) : std::string("haptic_node/") + user;
}

constexpr int kWarmup = 200;  // samples (or ticks) sent before the measured ones

std::int64_t Now() { return static_cast<std::int64_t>(common::SteadyNowNs()); }

void SleepUntilNs(std::int64_t t) {
  std::this_thread::sleep_until(std::chrono::steady_clock::time_point(std::chrono::nanoseconds(t)));
}

// A contact set as a hand pressing a deformable sends it: five fingers on one object.
msg::ContactSet MakeContactSet(const std::string& session) {
  msg::ContactSet s;
  s.user("net_bench");
  s.session(session);
  for (int i = 0; i < 5; ++i) {
    auto& f = s.fingers()[static_cast<std::size_t>(i)];
    f.active(true);
    f.object_id("triceratops_tail");
    f.surface_node(100 + i);
    f.p_OC_m({0.2 + 0.01 * i, 0.08, 0.065});
    f.n_O({0.0, 0.0, 1.0});
    f.p_OE_m({0.2 + 0.01 * i, 0.08, 0.07});
    f.radius_m(0.008);
    f.depth_m(0.003);
    f.u_O_m({0.0, 0.0, -0.003});
    f.f_O_N({0.0, 0.0, -0.7});
  }
  s.q_WO_wxyz({1.0, 0.0, 0.0, 0.0});
  return s;
}

// ---------------------------------------------------------------- the ends (child processes)

std::ofstream OpenOut(const std::string& path) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  return f;
}

void WaitForReader(dds::Writer<msg::ContactSet>& w) {
  const std::int64_t deadline = Now() + 20'000'000'000;
  while (w.matched_readers() == 0) {
    if (Now() > deadline) throw std::runtime_error("no reader matched within 20 s");
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  // The reader's side of the match may come a little later: best-effort samples before it are
  // lost, and the warm-up samples are not measured anyway.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
}

// Writer: serialization timing, then count + warm-up samples at rate_Hz on absolute deadlines.
// Rows: "ser NS", "deser NS", "w SEQ STAMP RETURNED".
int RunWriter(const Options& o) {
  dds::Participant p(o.domain, o.session, EndName(o, "net_bench_writer", "alice"), o.qos, o.security);
  auto w = dds::MakeWriter<msg::ContactSet>(p, dds::topics::kContactSet);
  msg::ContactSet s = MakeContactSet(o.session);
  std::ofstream out = OpenOut(o.out);
  msg::ContactSet back;
  for (int i = 0; i < 2000; ++i) {
    s.seq(static_cast<std::uint32_t>(i));
    const std::int64_t t0 = Now();
    const std::vector<std::uint8_t> bytes = dds::Serialize(s);
    const std::int64_t t1 = Now();
    dds::Deserialize<msg::ContactSet>(bytes, back);
    const std::int64_t t2 = Now();
    out << "ser " << (t1 - t0) << "\ndeser " << (t2 - t1) << "\n";
    if (i == 0) out << "bytes " << bytes.size() << "\n";
  }
  WaitForReader(w);
  const std::int64_t period = static_cast<std::int64_t>(1e9 / o.rate_Hz);
  std::vector<std::array<std::int64_t, 3>> rows;
  rows.reserve(static_cast<std::size_t>(o.count + kWarmup));
  std::int64_t next = Now();
  for (int i = 0; i < o.count + kWarmup; ++i) {
    next += period;
    SleepUntilNs(next);
    const std::int64_t stamp = Now();
    s.seq(static_cast<std::uint32_t>(i));
    s.stamp_ns(static_cast<std::uint64_t>(stamp));
    w.Write(s);
    rows.push_back({i, stamp, Now()});
  }
  for (const auto& r : rows) out << "w " << r[0] << ' ' << r[1] << ' ' << r[2] << "\n";
  // Let the last samples arrive before the participant goes.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  return 0;
}

// Reader: waits on its WaitSet, takes everything. Rows: "r SEQ STAMP WOKE TAKEN".
int RunReader(const Options& o) {
  dds::Participant p(o.domain, o.session, EndName(o, "net_bench_reader", "bob"), o.qos, o.security);
  auto r = dds::MakeReader<msg::ContactSet>(p, dds::topics::kContactSet);
  std::ofstream out = OpenOut(o.out);
  const int last = o.count + kWarmup - 1;
  std::vector<std::array<std::int64_t, 4>> rows;
  rows.reserve(static_cast<std::size_t>(o.count + kWarmup));
  msg::ContactSet s;
  dds::SampleMeta meta;
  const std::int64_t give_up = Now() + 60'000'000'000;
  std::int64_t last_data = 0;
  bool done = false;
  while (!done) {
    const std::int64_t now = Now();
    if (now > give_up || (last_data != 0 && now - last_data > 3'000'000'000)) break;
    if (!r.WaitForData(std::chrono::milliseconds(100))) continue;
    const std::int64_t woke = Now();
    while (r.TakeNext(s, meta)) {
      const std::int64_t taken = Now();
      if (!meta.valid_data) continue;
      rows.push_back({static_cast<std::int64_t>(s.seq()), static_cast<std::int64_t>(s.stamp_ns()), woke, taken});
      last_data = taken;
      if (static_cast<int>(s.seq()) >= last) done = true;
    }
  }
  for (const auto& x : rows) out << "r " << x[0] << ' ' << x[1] << ' ' << x[2] << ' ' << x[3] << "\n";
  return 0;
}

// The haptic node itself (HapticNode: its device, 1 kHz HapticLoop, SceneRenderer and
// HapticBridge on its bridge thread, the code haptic_node runs), as user alice or bob of a
// session whose scene `lab` (a soft block) is in o.assets; its simulated hand presses the block
// beside the other's, moving, so both hands share the block and their contact sets change.
// bob's process also plays the world server's part the bench needs: the scene state.
// The bridge's coupling trace (HapticNodeConfig::coupling_trace_file) is the result file.
int RunNode(const Options& o) {
  const fs::path assets(o.assets);
  const bool bob = o.user == "bob";
  haptic::HapticNodeConfig c;
  c.where.domain_id = o.domain;
  c.where.session = o.session;
  c.where.qos_file = o.qos;
  c.where.security_dir = o.security;
  c.where.duration = std::chrono::duration<double>(NodeSeconds(o));
  c.user = o.user;
  c.device = "sim";
  c.script = (assets / (o.user + ".hand")).string();
  c.cache_dir = (assets / ("cache_" + o.user)).string();  // one each: the two build it at once
  c.deadband_weber = o.node_weber;
  c.rejoin_after_s = 0.0;
  c.coupling_on_wake = o.node_coupling == "woken";
  c.coupling_trace_file = o.out;
  setenv("HANDSHARE_ASSETS", assets.c_str(), 1);
  std::unique_ptr<dds::Participant> server;
  dds::Writer<msg::SceneState> scene_writer;
  if (bob) {
    // Reliable, transient-local: alice gets it whenever she matches.
    server = std::make_unique<dds::Participant>(c.where, o.security.empty() ? "net_bench_scene" : "world_server");
    scene_writer = dds::MakeWriter<msg::SceneState>(*server, dds::topics::kSceneState);
    msg::SceneState scene;
    scene.session(o.session);
    scene.scene("lab");
    scene.revision(1);
    scene.gravity_W_m_per_s2({0.0, 0.0, -9.81});
    scene.tick_Hz(60.0f);
    scene_writer.Write(scene);
  }
  return haptic::HapticNode(c).Run();
}

// ---------------------------------------------------------------- the driver (--csv)

volatile sig_atomic_t g_interrupted = 0;
void OnSignal(int) { g_interrupted = 1; }

// Runs a command to completion, output discarded; returns its exit status (-1: not started).
int RunQuiet(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0], &fa, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

void MustRun(const std::vector<std::string>& argv) {
  if (RunQuiet(argv) != 0) {
    std::string cmd;
    for (const auto& a : argv) cmd += a + " ";
    throw std::runtime_error("failed: " + cmd);
  }
}

// Two namespaces (a, b) on a bridge, each with a veth "eth0" and multicast routed over it, as
// tests/net/netharness.py builds them. Removed in the destructor.
class NamespacePair {
 public:
  NamespacePair() : tag_("hsb" + std::to_string(getpid())) {
    try {
      MustRun({"ip", "link", "add", tag_ + "br", "type", "bridge", "mcast_snooping", "0"});
      made_bridge_ = true;
      MustRun({"ip", "link", "set", tag_ + "br", "up"});
      for (int k = 0; k < 2; ++k) {
        const std::string ns = Ns(k), port = tag_ + "p" + std::to_string(k);
        MustRun({"ip", "netns", "add", ns});
        made_ns_[k] = true;
        MustRun({"ip", "link", "add", port, "type", "veth", "peer", "name", "eth0", "netns", ns});
        MustRun({"ip", "link", "set", port, "master", tag_ + "br", "up"});
        MustRun({"ip", "-n", ns, "addr", "add", "10.251.0." + std::to_string(k + 1) + "/24", "dev", "eth0"});
        MustRun({"ip", "-n", ns, "link", "set", "eth0", "up"});
        MustRun({"ip", "-n", ns, "link", "set", "lo", "up"});
        MustRun({"ip", "-n", ns, "route", "add", "224.0.0.0/4", "dev", "eth0"});
      }
    } catch (...) {
      Remove();
      throw;
    }
  }
  ~NamespacePair() { Remove(); }
  NamespacePair(const NamespacePair&) = delete;
  NamespacePair& operator=(const NamespacePair&) = delete;
  std::string Ns(int k) const { return tag_ + (k == 0 ? "a" : "b"); }

 private:
  void Remove() {
    for (int k = 0; k < 2; ++k) {
      // The veth pair goes with its namespace end.
      if (made_ns_[k]) RunQuiet({"ip", "netns", "del", Ns(k)});
      made_ns_[k] = false;
      RunQuiet({"ip", "link", "del", tag_ + "p" + std::to_string(k)});
    }
    if (made_bridge_) RunQuiet({"ip", "link", "del", tag_ + "br"});
    made_bridge_ = false;
  }
  std::string tag_;
  bool made_bridge_ = false;
  std::array<bool, 2> made_ns_{false, false};
};

// Why netns cannot run here, or "" if it can.
std::string NetnsUnavailable() {
  if (geteuid() != 0) return "needs root (network namespaces, veth, bridge)";
  if (RunQuiet({"ip", "-V"}) != 0) return "'ip' not found (Debian package iproute2)";
  return "";
}

// The project's QoS file with the participant's builtin transports replaced by one user
// transport: the transport under test is the only way between the two ends.
std::string ForcedTransportQos(const std::string& transport, const fs::path& dir) {
  const std::string source = dds::DefaultQosFile();
  std::ifstream in(source);
  if (!in) throw std::runtime_error("cannot read the QoS file " + source);
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string xml = buffer.str();
  const bool shm = transport == "shm";
  const std::string descriptor = std::string("<transport_descriptors><transport_descriptor>") +
                                 "<transport_id>net_bench_transport</transport_id><type>" +
                                 (shm ? "SHM" : "UDPv4") + "</type></transport_descriptor></transport_descriptors>";
  const std::string participant_tag = "<participant profile_name=\"handshare_participant\">";
  const std::string use = "<userTransports><transport_id>net_bench_transport</transport_id></userTransports>"
                          "<useBuiltinTransports>false</useBuiltinTransports>";
  const auto profiles = xml.find("<profiles>");
  const auto participant = xml.find(participant_tag);
  const auto rtps = participant == std::string::npos ? std::string::npos : xml.find("<rtps>", participant);
  if (profiles == std::string::npos || rtps == std::string::npos) {
    throw std::runtime_error(source + ": no <profiles> or no participant profile 'handshare_participant' with <rtps>");
  }
  // The file's own transport list (and builtin switch) in that profile goes: one of each.
  for (const std::string tag : {"userTransports", "useBuiltinTransports"}) {
    const auto open = xml.find("<" + tag + ">", rtps);
    const auto end = xml.find("</participant>", rtps);
    if (open == std::string::npos || open > end) continue;
    const std::string closing = "</" + tag + ">";
    const auto close = xml.find(closing, open);
    if (close == std::string::npos) throw std::runtime_error(source + ": <" + tag + "> without its end");
    xml.erase(open, close + closing.size() - open);
  }
  xml.insert(rtps + std::strlen("<rtps>"), use);
  xml.insert(profiles + std::strlen("<profiles>"), descriptor);
  const fs::path file = dir / ("qos_" + transport + ".xml");
  std::ofstream(file) << xml;
  return file.string();
}

struct Child {
  pid_t pid = -1;
  std::string label;
};

Child Spawn(const std::vector<std::string>& argv, const std::string& log, const std::string& label) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, args[0], &fa, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(rc));
  return Child{pid, label};
}

std::string ReadAll(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Waits for both ends; kills them after timeout_s or on SIGINT/SIGTERM. Throws if one failed.
void WaitBoth(std::array<Child, 2> children, const std::array<std::string, 2>& logs, double timeout_s) {
  const std::int64_t deadline = Now() + static_cast<std::int64_t>(timeout_s * 1e9);
  std::array<int, 2> status{-1, -1};
  int running = 2;
  std::string failure;
  while (running > 0) {
    for (int k = 0; k < 2; ++k) {
      if (children[k].pid < 0) continue;
      int st = 0;
      if (waitpid(children[k].pid, &st, WNOHANG) == children[k].pid) {
        status[k] = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        children[k].pid = -1;
        --running;
      }
    }
    if (running == 0) break;
    if (g_interrupted || Now() > deadline) {
      failure = g_interrupted ? "interrupted" : "timed out after " + std::to_string(static_cast<int>(timeout_s)) + " s";
      for (auto& c : children) {
        if (c.pid > 0) kill(c.pid, SIGKILL);
      }
      for (auto& c : children) {
        if (c.pid > 0) waitpid(c.pid, nullptr, 0);
      }
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  for (int k = 0; k < 2 && failure.empty(); ++k) {
    if (status[k] != 0) failure = children[k].label + " exited with status " + std::to_string(status[k]);
  }
  if (!failure.empty()) {
    throw std::runtime_error(failure + "\n--- " + children[0].label + ":\n" + ReadAll(logs[0]) + "--- " +
                             children[1].label + ":\n" + ReadAll(logs[1]));
  }
}

struct Row {
  std::string tag;
  std::vector<std::int64_t> v;
};

std::vector<Row> ReadRows(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("missing result file " + path);
  std::vector<Row> rows;
  std::string line;
  while (std::getline(f, line)) {
    std::istringstream s(line);
    Row r;
    s >> r.tag;
    std::int64_t x = 0;
    while (s >> x) r.v.push_back(x);
    rows.push_back(std::move(r));
  }
  return rows;
}

void PrintRow(const std::string& transport, const std::string& measure, std::vector<double> us) {
  if (us.empty()) {
    std::printf("# %s %s: no samples\n", transport.c_str(), measure.c_str());
    return;
  }
  std::sort(us.begin(), us.end());
  auto at = [&](double q) {
    const auto i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(us.size()))) - 1;
    return us[std::min(i, us.size() - 1)];
  };
  std::printf("%s,%s,%.1f,%.1f,%.1f\n", transport.c_str(), measure.c_str(), at(0.50), at(0.99), us.back());
  std::fflush(stdout);
}

std::string LoadAvg() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

// The bare hop: writer and reader processes.
void MeasureHop(const Options& o, const std::string& transport, const std::string& qos, const fs::path& dir,
                const NamespacePair* ns, int domain) {
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const std::string session = "net_bench_" + std::to_string(getpid()) + "_" + transport;
  auto argv = [&](const std::string& role, const std::string& out, int k) {
    std::vector<std::string> a;
    if (ns != nullptr) a = {"ip", "netns", "exec", ns->Ns(k)};
    a.insert(a.end(), {self, "--role", role, "--qos", qos, "--domain", std::to_string(domain), "--session", session,
                       "--count", std::to_string(o.count), "--node-count", std::to_string(o.node_count), "--rate",
                       std::to_string(o.rate_Hz), "--out", out});
    if (o.fifo > 0) a.insert(a.end(), {"--fifo", std::to_string(o.fifo)});
    if (!o.security.empty()) a.insert(a.end(), {"--security", o.security});
    return a;
  };
  const std::string rf = (dir / (transport + "_reader.txt")).string(), wf = (dir / (transport + "_writer.txt")).string();
  const std::array<std::string, 2> logs{(dir / (transport + "_reader.log")).string(),
                                        (dir / (transport + "_writer.log")).string()};
  Child reader = Spawn(argv("reader", rf, 0), logs[0], transport + " reader");
  Child writer = Spawn(argv("writer", wf, 1), logs[1], transport + " writer");
  WaitBoth({reader, writer}, logs, 60.0 + o.count / o.rate_Hz);

  std::map<std::int64_t, std::array<std::int64_t, 2>> sent;  // seq -> stamp, returned
  std::vector<double> ser, deser, write_call;
  std::int64_t bytes = 0;
  for (const Row& r : ReadRows(wf)) {
    if (r.tag == "ser") ser.push_back(1e-3 * static_cast<double>(r.v.at(0)));
    if (r.tag == "deser") deser.push_back(1e-3 * static_cast<double>(r.v.at(0)));
    if (r.tag == "bytes") bytes = r.v.at(0);
    if (r.tag == "w" && r.v.at(0) >= kWarmup) {
      sent[r.v[0]] = {r.v[1], r.v[2]};
      write_call.push_back(1e-3 * static_cast<double>(r.v[2] - r.v[1]));
    }
  }
  std::vector<double> one_way, to_wake, to_taken;
  for (const Row& r : ReadRows(rf)) {
    if (r.tag != "r" || r.v.at(0) < kWarmup) continue;
    const auto it = sent.find(r.v[0]);
    if (it == sent.end()) continue;
    one_way.push_back(1e-3 * static_cast<double>(r.v[3] - r.v[1]));
    to_wake.push_back(1e-3 * static_cast<double>(r.v[2] - it->second[1]));
    to_taken.push_back(1e-3 * static_cast<double>(r.v[3] - r.v[2]));
  }
  std::printf("# %s: %zu of %zu samples taken (keep-last 1: a sample not taken before the next one is "
              "replaced) (%lld bytes CDR each, %.0f Hz), load %s\n", transport.c_str(),
              one_way.size(), sent.size(), static_cast<long long>(bytes), o.rate_Hz, LoadAvg().c_str());
  PrintRow(transport, std::string("contact_one_way") + Secured(o), one_way);
  PrintRow(transport, std::string("serialize") + Secured(o), ser);
  PrintRow(transport, std::string("deserialize") + Secured(o), deser);
  PrintRow(transport, std::string("write_call") + Secured(o), write_call);
  PrintRow(transport, std::string("write_to_wake") + Secured(o), to_wake);
  PrintRow(transport, std::string("wake_to_taken") + Secured(o), to_taken);
}

// The lab scene and the two hands of the node path (RunNode), written to dir/assets.
fs::path WriteNodeAssets(const fs::path& dir) {
  const fs::path assets = dir / "assets";
  fs::create_directories(assets / "scenes");
  // A soft block on the ground: its top is at z = 0.02 m, x in -0.12..-0.08, y in -0.02..0.02.
  std::ofstream(assets / "scenes" / "lab.json")
      << R"({"name": "lab", "gravity_m_per_s2": [0, 0, -9.81], "objects": [
  {"id": "ground", "kind": "rigid", "shape": "box", "position_m": [0, 0, -0.02], "half_extent_m": [0.3, 0.3, 0.02]},
  {"id": "block", "kind": "deformable", "shape": "box", "position_m": [-0.1, 0, 0.01],
   "half_extent_m": [0.02, 0.02, 0.01], "material": {"E_Pa": 20000, "nu": 0.4}, "fixed": {"below_m": -0.0099}}],
  "messages": [{"language": "en", "text": "net_bench", "next_action": "none"}]})";
  // Each index fingertip (radius 8 mm: touching at z = 0.028 m) presses 1 to 3 mm into the
  // top, 10 mm from the other's, in and out every 0.4 s (alice and bob out of step).
  for (const auto& [user, x, phase] : {std::tuple{"alice", -0.105, 0.0}, std::tuple{"bob", -0.095, 0.13}}) {
    std::ofstream f(assets / (std::string(user) + ".hand"));
    f << "start " << x << " 0 0.08\nawait_world lab\npoke 0.5 " << x << " 0 0.027\n";
    if (phase > 0.0) f << "hold " << phase << "\n";
    for (int i = 0; i < 400; ++i) f << "poke 0.2 " << x << " 0 0.025\npoke 0.2 " << x << " 0 0.027\n";
  }
  return assets;
}

// The node path: two haptic nodes' own code (RunNode), each pressing the block with the
// other, their bridges' coupling traces paired by the contact set's stamp (its sender's
// write() call): both directions. The first second of each node's writes is a warm-up.
void MeasureNodePath(const Options& o, const std::string& transport, const std::string& qos, const fs::path& dir,
                     const NamespacePair* ns, int domain) {
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const std::string session = "net_bench_" + std::to_string(getpid()) + "_node_" + transport;
  const fs::path assets = WriteNodeAssets(dir);
  auto argv = [&](const std::string& user, const std::string& out, int k) {
    std::vector<std::string> a;
    if (ns != nullptr) a = {"ip", "netns", "exec", ns->Ns(k)};
    a.insert(a.end(), {self, "--role", "node", "--user", user, "--qos", qos, "--domain", std::to_string(domain),
                       "--session", session, "--node-count", std::to_string(o.node_count), "--assets",
                       assets.string(), "--node-weber", std::to_string(o.node_weber), "--node-coupling",
                       o.node_coupling, "--out", out});
    if (o.fifo > 0) a.insert(a.end(), {"--fifo", std::to_string(o.fifo)});
    if (!o.security.empty()) a.insert(a.end(), {"--security", o.security});
    return a;
  };
  const std::array<std::string, 2> users{"bob", "alice"};
  std::array<std::string, 2> files, logs;
  for (int k = 0; k < 2; ++k) {
    files[k] = (dir / (transport + "_node_" + users[k] + ".txt")).string();
    logs[k] = (dir / (transport + "_node_" + users[k] + ".log")).string();
  }
  Child bob = Spawn(argv(users[0], files[0], 0), logs[0], transport + " node bob");
  Child alice = Spawn(argv(users[1], files[1], 1), logs[1], transport + " node alice");
  WaitBoth({bob, alice}, logs, 60.0 + NodeSeconds(o));

  // Per node: its writes by stamp (the step that made the set, write() called and returned),
  // and the peers' sets it took (by stamp) and first used in a haptic step (by stamp).
  struct Written {
    std::int64_t step, call, done;
  };
  std::array<std::map<std::int64_t, Written>, 2> written;
  std::array<std::map<std::int64_t, std::int64_t>, 2> taken, used;
  for (int k = 0; k < 2; ++k) {
    std::int64_t first_write = -1;
    for (const Row& r : ReadRows(files[k])) {
      if (r.v.size() < 4) continue;
      if (r.tag == "w") {
        if (first_write < 0) first_write = r.v[2];
        if (r.v[2] - first_write >= 1'000'000'000) written[k][r.v[2]] = Written{r.v[1], r.v[2], r.v[3]};
      }
      if (r.tag == "t") taken[k][r.v[0]] = r.v[1];
      if (r.tag == "u") used[k].emplace(r.v[0], r.v[1]);
    }
  }
  std::vector<double> total, sender, hop, receiver, write_call;
  std::size_t writes = 0;
  for (int k = 0; k < 2; ++k) {
    const int peer = 1 - k;
    writes += written[k].size();
    for (const auto& [stamp, w] : written[k]) {
      const auto t = taken[peer].find(stamp);
      const auto u = used[peer].find(stamp);
      if (t == taken[peer].end() || u == used[peer].end()) continue;
      total.push_back(1e-3 * static_cast<double>(u->second - w.step));
      sender.push_back(1e-3 * static_cast<double>(w.call - w.step));
      write_call.push_back(1e-3 * static_cast<double>(w.done - w.call));
      hop.push_back(1e-3 * static_cast<double>(t->second - w.call));
      receiver.push_back(1e-3 * static_cast<double>(u->second - t->second));
    }
  }
  const double seconds = NodeSeconds(o);
  std::printf("# %s node path (haptic_node's own loop and bridge, coupling %s, deadband weber %.2f): %zu contact "
              "sets written after the warm-up (%.0f per second per node), %zu first used by the peer's haptic step "
              "and counted; load %s\n",
              transport.c_str(), o.node_coupling.c_str(), o.node_weber, writes,
              static_cast<double>(writes) / 2.0 / std::max(1.0, seconds - 3.0), total.size(), LoadAvg().c_str());
  PrintRow(transport, std::string("node_path") + Secured(o), total);
  PrintRow(transport, std::string("node_sender_handoff") + Secured(o), sender);
  PrintRow(transport, std::string("node_write_call") + Secured(o), write_call);
  PrintRow(transport, std::string("node_dds_and_tick") + Secured(o), hop);
  PrintRow(transport, std::string("node_receiver_handoff") + Secured(o), receiver);
}

int RunCsv(const Options& o) {
  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGHUP, &sa, nullptr);
  const fs::path dir = o.keep.empty() ? fs::temp_directory_path() / ("net_bench." + std::to_string(getpid()))
                                      : fs::path(o.keep);
  fs::create_directories(dir);
  std::printf("# net_bench: %d samples at %.0f Hz per transport, node path %.0f s per transport (coupling %s); %s; %s; "
              "load before %s\n",
              o.count, o.rate_Hz, NodeSeconds(o), o.node_coupling.c_str(),
              o.security.empty() ? "no security" : ("DDS-Security with keystore " + o.security).c_str(),
              o.fifo > 0 ? ("both ends SCHED_FIFO " + std::to_string(o.fifo) + " (every thread)").c_str()
                         : "both ends at normal priority (the haptic nodes' loops SCHED_FIFO when permitted, as HapticLoop)",
              LoadAvg().c_str());
  std::printf("transport,measure,p50_us,p99_us,max_us\n");
  std::fflush(stdout);
  int status = 0;
  int domain = o.domain;
  for (const std::string& t : o.transports) {
    if (g_interrupted) break;
    try {
      std::unique_ptr<NamespacePair> ns;
      if (t == "netns") {
        if (const std::string why = NetnsUnavailable(); !why.empty()) {
          std::printf("# netns: skipped: %s\n", why.c_str());
          continue;
        }
        ns = std::make_unique<NamespacePair>();
      }
      const std::string qos = ForcedTransportQos(t == "shm" ? "shm" : "udp", dir);
      // A domain per run: no run discovers a participant an earlier one left in its lease.
      MeasureHop(o, t, qos, dir, ns.get(), domain++);
      if (o.node_count > 0 && !g_interrupted) MeasureNodePath(o, t, qos, dir, ns.get(), domain++);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "net_bench: %s: %s\n", t.c_str(), e.what());
      status = 1;
    }
  }
  std::printf("# load after %s\n", LoadAvg().c_str());
  // Segments of ends that were killed; those of live processes stay.
  RunQuiet({"fastdds", "shm", "clean"});
  if (o.keep.empty()) fs::remove_all(dir);
  if (g_interrupted) return 130;
  return status;
}

// ---------------------------------------------------------------- options

const char* kUsage =
    "usage: net_bench --csv [--count N] [--rate HZ] [--node-count N] [--domain D] [--transports shm,udp,netns]\n"
    "                 [--fifo PRIO] [--keep DIR] [--security KEYSTORE]\n"
    "                 [--node-coupling woken|polled] [--node-weber W]\n"
    "       net_bench --role writer|reader|node --qos FILE --domain D --session S --out FILE\n"
    "                 [--count N] [--node-count N] [--rate HZ] [--user alice|bob --assets DIR]\n"
    "Prints transport,measure,p50_us,p99_us,max_us rows; see the top of bench/net/net_bench.cpp.\n";

int ToInt(const std::string& flag, const std::string& v, int lo, int hi) {
  try {
    std::size_t used = 0;
    const long x = std::stol(v, &used);
    if (used == v.size() && x >= lo && x <= hi) return static_cast<int>(x);
  } catch (const std::exception&) {
  }
  throw UsageError(flag + " wants an integer in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got '" + v + "'");
}

Options Parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw UsageError(a + " needs a value");
      return argv[++i];
    };
    if (a == "--csv") {
      o.csv = true;
    } else if (a == "--role") {
      o.role = value();
    } else if (a == "--qos") {
      o.qos = value();
    } else if (a == "--session") {
      o.session = value();
    } else if (a == "--out") {
      o.out = value();
    } else if (a == "--keep") {
      o.keep = value();
    } else if (a == "--security") {
      o.security = fs::absolute(value()).string();
    } else if (a == "--domain") {
      o.domain = ToInt(a, value(), 0, 232);
    } else if (a == "--fifo") {
      o.fifo = ToInt(a, value(), 1, 99);
    } else if (a == "--count") {
      o.count = ToInt(a, value(), 1, 10'000'000);
    } else if (a == "--node-count") {
      o.node_count = ToInt(a, value(), 0, 1'000'000);
    } else if (a == "--rate") {
      const std::string v = value();
      char* end = nullptr;
      o.rate_Hz = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !(o.rate_Hz >= 1.0 && o.rate_Hz <= 100000.0)) {
        throw UsageError("--rate wants a rate in Hz in 1..100000, got '" + v + "'");
      }
    } else if (a == "--transports") {
      o.transports.clear();
      std::stringstream s(value());
      std::string t;
      while (std::getline(s, t, ',')) {
        if (t != "shm" && t != "udp" && t != "netns") {
          throw UsageError("--transports: unknown transport '" + t + "' (shm, udp, netns)");
        }
        o.transports.push_back(t);
      }
      if (o.transports.empty()) throw UsageError("--transports is empty");
    } else if (a == "--user") {
      o.user = value();
      if (o.user != "alice" && o.user != "bob") throw UsageError("--user wants alice or bob, got '" + o.user + "'");
    } else if (a == "--assets") {
      o.assets = value();
    } else if (a == "--node-coupling") {
      o.node_coupling = value();
      if (o.node_coupling != "woken" && o.node_coupling != "polled") {
        throw UsageError("--node-coupling wants woken or polled, got '" + o.node_coupling + "'");
      }
    } else if (a == "--node-weber") {
      const std::string v = value();
      char* end = nullptr;
      o.node_weber = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !(o.node_weber >= 0.0 && o.node_weber <= 1.0)) {
        throw UsageError("--node-weber wants a Weber fraction in 0..1, got '" + v + "'");
      }
    } else if (a == "--help" || a == "-h") {
      std::fputs(kUsage, stdout);
      std::exit(0);
    } else {
      throw UsageError("unknown option '" + a + "'");
    }
  }
  if (o.csv == !o.role.empty()) throw UsageError("give either --csv or --role");
  if (!o.role.empty()) {
    if (o.role != "writer" && o.role != "reader" && o.role != "node") {
      throw UsageError("unknown --role '" + o.role + "'");
    }
    if (o.role == "node" && (o.user.empty() || o.assets.empty())) throw UsageError("--role node needs --user and --assets");
    if (o.qos.empty() || o.session.empty() || o.out.empty()) throw UsageError("--role needs --qos, --session and --out");
  }
  if (o.csv && o.domain + 2 * static_cast<int>(o.transports.size()) > 233) throw UsageError("--domain too high");
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  try {
    o = Parse(argc, argv);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "net_bench: %s\n%s", e.what(), kUsage);
    return 2;
  }
  try {
    if (!o.csv && o.fifo > 0) {
      // Before the participant: Fast DDS's receive and event threads inherit the policy.
      sched_param param{};
      param.sched_priority = o.fifo;
      if (sched_setscheduler(0, SCHED_FIFO, &param) != 0) {
        throw std::runtime_error("--fifo " + std::to_string(o.fifo) + ": SCHED_FIFO refused: " + std::strerror(errno));
      }
    }
    if (o.csv) return RunCsv(o);
    if (o.role == "writer") return RunWriter(o);
    if (o.role == "reader") return RunReader(o);
    return RunNode(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "net_bench: %s\n", e.what());
    return 1;
  }
}
