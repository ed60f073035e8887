// qos_probe: measures what the QoS profiles do on a real (impaired) link, with the project's
// own typed DDS layer and the topics' own profiles (core/dds/include/handshare/dds/topics.hpp).
// One process publishes (--role pub), another on another host reads (--role sub); both print
// one line that tests/net/qos_measure.py parses. Cases:
//   event    ControlEvent (event profile: reliable, keep-all) at --rate; latency from the
//            sample's stamp_ns (steady clock: hosts in network namespaces share one kernel).
//   field    Deformation (bulk profile) of --nodes surface nodes at --rate; latency from the
//            sample's source timestamp (taken at write(), also for an asynchronous writer).
//   contact  ContactSet (contact stream profile) at --rate, while Deformations of --nodes nodes
//            go at --field-rate from the same participant on the same link; latency of the
//            contact sets from stamp_ns.
// The subscriber reports how many of --count samples arrived, the one-way latency p50, p99 and
// max, and how many arrived within --within-ms. Not a node: a test tool.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "handshare/node/node_main.hpp"
#include "handshare/common/options.hpp"
#include "handshare/common/shutdown.hpp"
#include "handshare/dds/messages.hpp"

namespace {

using namespace handshare;
using Clock = std::chrono::steady_clock;

std::int64_t SteadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}
std::int64_t WallNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

msg::Deformation Field(const std::string& session, std::uint32_t nodes) {
  msg::Deformation d;
  d.object_id("tail");
  d.session(session);
  d.keyframe(true);
  d.surface_node_count(nodes);
  std::vector<std::uint32_t> ids(nodes);
  std::vector<float> u(3 * static_cast<std::size_t>(nodes));
  for (std::uint32_t i = 0; i < nodes; ++i) {
    ids[i] = i;
    u[3 * i] = 1e-4f * static_cast<float>(i % 17);
    u[3 * i + 1] = -2e-4f;
    u[3 * i + 2] = 3e-5f * static_cast<float>(i % 5);
  }
  d.node_ids(ids);
  d.u_W_m(u);
  return d;
}

// Waits until a writer has a matched reader: the count starts when the reader can get it.
template <class W>
bool WaitMatched(const W& w, std::chrono::seconds timeout) {
  const auto end = Clock::now() + timeout;
  while (w.matched_readers() == 0) {
    if (Clock::now() > end || common::ShutdownRequested()) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

// Sends at a fixed rate (absolute deadlines, re-sync rather than burst) count times.
template <class Send>
std::uint32_t Paced(double rate_Hz, std::uint32_t count, const std::atomic<bool>& stop, Send send) {
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / rate_Hz));
  auto next = Clock::now();
  std::uint32_t sent = 0;
  while (sent < count && !stop && !common::ShutdownRequested()) {
    send(sent);
    ++sent;
    next += period;
    if (Clock::now() > next + 5 * period) next = Clock::now();
    std::this_thread::sleep_until(next);
  }
  return sent;
}

int Publish(const common::Options& o, const common::SessionOptions& where, const std::string& which) {
  const double rate_Hz = o.GetDouble("rate", 0.1, 10000.0);
  const auto count = static_cast<std::uint32_t>(o.GetInt("count", 1, 10000000));
  const auto nodes = static_cast<std::uint32_t>(o.GetInt("nodes", 1, msg::kMaxSurfaceDelta));
  const double field_rate_Hz = o.GetDouble("field-rate", 0.0, 1000.0);
  const double linger_s = o.GetDouble("linger", 0.0, 600.0);
  dds::Participant participant(where, "qos_probe_pub");
  std::atomic<bool> stop{false};
  std::uint32_t sent = 0;
  const auto started = Clock::now();
  if (which == "event") {
    auto events = dds::MakeWriter<msg::ControlEvent>(participant, dds::topics::kControlEvent);
    if (!WaitMatched(events, std::chrono::seconds(60))) throw std::runtime_error("no reader matched in 60 s");
    std::printf("matched\n");
    std::fflush(stdout);
    msg::ControlEvent e;
    e.session(where.session);
    e.user("probe");
    e.control_id("button");
    e.kind(msg::CONTROL_PRESSED);
    sent = Paced(rate_Hz, count, stop, [&](std::uint32_t k) {
      e.index(static_cast<std::int32_t>(k));
      e.stamp_ns(static_cast<std::uint64_t>(SteadyNs()));
      events.Write(e);
    });
  } else if (which == "field") {
    auto fields = dds::MakeWriter<msg::Deformation>(participant, dds::topics::kDeformation);
    if (!WaitMatched(fields, std::chrono::seconds(60))) throw std::runtime_error("no reader matched in 60 s");
    std::printf("matched\n");
    std::fflush(stdout);
    msg::Deformation d = Field(where.session, nodes);
    sent = Paced(rate_Hz, count, stop, [&](std::uint32_t k) {
      d.revision(k);
      fields.Write(d);
    });
  } else {
    auto contacts = dds::MakeWriter<msg::ContactSet>(participant, dds::topics::kContactSet);
    auto fields = dds::MakeWriter<msg::Deformation>(participant, dds::topics::kDeformation);
    if (!WaitMatched(contacts, std::chrono::seconds(60)) ||
        (field_rate_Hz > 0 && !WaitMatched(fields, std::chrono::seconds(60)))) {
      throw std::runtime_error("no reader matched in 60 s");
    }
    std::printf("matched\n");
    std::fflush(stdout);
    // The fields on their own thread, as the world server's tick publishes them.
    std::thread field_thread;
    if (field_rate_Hz > 0) {
      field_thread = std::thread([&] {
        msg::Deformation d = Field(where.session, nodes);
        Paced(field_rate_Hz, 10000000, stop, [&](std::uint32_t k) {
          d.revision(k);
          fields.Write(d);
        });
      });
    }
    msg::ContactSet c;
    c.session(where.session);
    c.user("probe");
    c.fingers()[1].active(true);
    c.fingers()[1].object_id("tail");
    c.q_WO_wxyz({1.0, 0.0, 0.0, 0.0});
    sent = Paced(rate_Hz, count, stop, [&](std::uint32_t k) {
      c.seq(k);
      c.stamp_ns(static_cast<std::uint64_t>(SteadyNs()));
      contacts.Write(c);
    });
    stop = true;
    if (field_thread.joinable()) field_thread.join();
  }
  std::printf("sent %u in %.2f s\n", sent, std::chrono::duration<double>(Clock::now() - started).count());
  std::fflush(stdout);
  // Reliable samples still being repaired need their writer.
  common::SleepUnlessShutdown(std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::duration<double>(linger_s)));
  return 0;
}

struct Received {
  std::vector<double> latency_ms;  // by sequence number; < 0: not (yet) received
  std::uint32_t duplicates = 0;
  std::uint32_t got = 0;
  explicit Received(std::uint32_t count) : latency_ms(count, -1.0) {}
  void Add(std::int64_t seq, double ms) {
    if (seq < 0 || static_cast<std::size_t>(seq) >= latency_ms.size()) return;
    if (latency_ms[static_cast<std::size_t>(seq)] >= 0) {
      ++duplicates;
      return;
    }
    latency_ms[static_cast<std::size_t>(seq)] = ms;
    ++got;
  }
};

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return -1.0;
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  return v[std::min(k, v.size() - 1)];
}

/// Takes `reader`'s samples until `stop()`, handing each one with data to `on_sample`.
template <class T, class Stop, class OnSample>
void Drain(dds::Reader<T>& reader, Stop stop, OnSample on_sample) {
  T sample;
  dds::SampleMeta meta;
  while (!stop()) {
    reader.WaitForData(std::chrono::milliseconds(50));
    while (reader.TakeNext(sample, meta)) {
      if (meta.valid_data) on_sample(sample, meta);
    }
  }
}

int Subscribe(const common::Options& o, const common::SessionOptions& where, const std::string& which) {
  const auto count = static_cast<std::uint32_t>(o.GetInt("count", 1, 10000000));
  const double within_ms = o.GetDouble("within-ms", 0.0, 100000.0);
  dds::Participant participant(where, "qos_probe_sub");
  Received r(count);
  std::uint64_t fields = 0;
  const auto start = Clock::now();
  const auto until = [&] {
    return common::ShutdownRequested() || r.got == count ||
           (where.duration.count() > 0 && Clock::now() - start > where.duration);
  };
  if (which == "event") {
    auto events = dds::MakeReader<msg::ControlEvent>(participant, dds::topics::kControlEvent);
    std::printf("ready\n");
    std::fflush(stdout);
    Drain(events, until, [&](const msg::ControlEvent& e, const dds::SampleMeta&) {
      r.Add(e.index(), 1e-6 * static_cast<double>(SteadyNs() - static_cast<std::int64_t>(e.stamp_ns())));
    });
  } else if (which == "field") {
    auto reader = dds::MakeReader<msg::Deformation>(participant, dds::topics::kDeformation);
    std::printf("ready\n");
    std::fflush(stdout);
    Drain(reader, until, [&](const msg::Deformation& d, const dds::SampleMeta& meta) {
      const double ms = 1e-6 * static_cast<double>(WallNs() - meta.source_timestamp_ns);
      // A sample is whole or not delivered at all; check it anyway (a torn field is a bug).
      if (d.node_ids().size() != d.surface_node_count() || d.u_W_m().size() != 3 * d.node_ids().size()) {
        std::printf("torn field: revision %u, %zu ids of %u\n", d.revision(), d.node_ids().size(),
                    d.surface_node_count());
        return;
      }
      r.Add(d.revision(), ms);
    });
  } else {
    auto contacts = dds::MakeReader<msg::ContactSet>(participant, dds::topics::kContactSet);
    auto reader = dds::MakeReader<msg::Deformation>(participant, dds::topics::kDeformation);
    std::atomic<bool> done{false};
    // Fields are read (they are only sent to a matched reader) on their own thread.
    std::thread field_thread([&] {
      Drain(reader, [&] { return done.load(); }, [&](const msg::Deformation&, const dds::SampleMeta&) { ++fields; });
    });
    std::printf("ready\n");
    std::fflush(stdout);
    Drain(contacts, until, [&](const msg::ContactSet& c, const dds::SampleMeta&) {
      r.Add(c.seq(), 1e-6 * static_cast<double>(SteadyNs() - static_cast<std::int64_t>(c.stamp_ns())));
    });
    done = true;
    field_thread.join();
  }
  std::vector<double> got;
  std::uint32_t in_time = 0;
  for (double ms : r.latency_ms) {
    if (ms < 0) continue;
    got.push_back(ms);
    if (ms <= within_ms) ++in_time;
  }
  std::printf("result case=%s expected=%u received=%u within=%u within_ms=%.1f p50_ms=%.2f p99_ms=%.2f "
              "max_ms=%.2f duplicates=%u fields=%llu\n",
              which.c_str(), count, r.got, in_time, within_ms, Quantile(got, 0.5), Quantile(got, 0.99),
              got.empty() ? -1.0 : *std::max_element(got.begin(), got.end()), r.duplicates,
              static_cast<unsigned long long>(fields));
  std::fflush(stdout);
  return 0;
}

int Run(const common::Options& o) {
  const common::SessionOptions where = node::ReadSessionOptions(o);
  const std::string role = o.GetString("role");
  const std::string which = o.GetString("case");
  if (which != "event" && which != "field" && which != "contact") {
    throw common::OptionError("--case: event, field or contact, not '" + which + "'");
  }
  if (role == "pub") return Publish(o, where, which);
  if (role == "sub") return Subscribe(o, where, which);
  throw common::OptionError("--role: pub or sub, not '" + role + "'");
}

}  // namespace

int main(int argc, char** argv) {
  handshare::common::Options options("qos_probe",
                                     "Measures delivery of reliable events, deformation fields and contact sets "
                                     "with the project's QoS profiles (tests/net/qos_measure.py drives it).");
  handshare::node::DeclareSessionOptions(options);
  options.Value("role", "pub|sub", "publish or subscribe", std::nullopt, true)
      .Value("case", "event|field|contact", "what to measure", std::nullopt, true)
      .Value("rate", "HZ", "samples per second of the measured topic", "10")
      .Value("count", "N", "samples of the measured topic", "100")
      .Value("nodes", "N", "surface nodes per Deformation (962: the triceratops tail)", "962")
      .Value("field-rate", "HZ", "contact case: Deformations per second on the same link (0: none)", "0")
      .Value("linger", "SEC", "pub: keep the writer this long after the last sample (repairs)", "3")
      .Value("within-ms", "MS", "sub: also count the samples that arrived within this", "100");
  return handshare::node::RunNodeMain(argc, argv, options,
                                        [](const handshare::common::Options& o) { return Run(o); });
}
