// security_probe: an outsider's (or an insider's) view of a session, for the security tests.
// Joins the session with the identity --as picks in the keystore --security DIR (or with no
// security at all), creates a reader and a writer on every topic of the session (where its
// own permissions refuse one, it says so and goes on), and watches until --duration passes
// or SIGTERM: how many of the session's writers and readers it matched and how many samples
// it read. A line "probe: ..." is printed whenever a figure grows, and once at the end with
// "final", so a test can wait for the first and compare the last.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "handshare/node/node_main.hpp"
#include "handshare/common/options.hpp"
#include "handshare/common/shutdown.hpp"
#include "handshare/dds/messages.hpp"

namespace {

using namespace handshare;

// One topic's reader and writer, type-erased for the loop below.
class TopicProbe {
 public:
  virtual ~TopicProbe() = default;
  virtual int matched_writers() const = 0;
  virtual int matched_readers() const = 0;
  virtual long TakeAll() = 0;  // samples with data read now
};

template <class T>
class TypedProbe final : public TopicProbe {
 public:
  TypedProbe(dds::Participant& p, const dds::topics::TopicSpec& spec, std::vector<std::string>& refused) {
    // Refused entities are what access control is for: note them, watch the rest.
    try {
      reader_ = dds::MakeReader<T>(p, spec);
    } catch (const dds::DdsError&) {
      refused.push_back(std::string("reader ") + spec.name);
    }
    try {
      writer_ = dds::MakeWriter<T>(p, spec);
    } catch (const dds::DdsError&) {
      refused.push_back(std::string("writer ") + spec.name);
    }
  }
  // The session's endpoints only: a participant's own reader and writer of a topic match
  // each other.
  int matched_writers() const override { return reader_ ? std::max(0, reader_.matched_writers() - (writer_ ? 1 : 0)) : 0; }
  int matched_readers() const override { return writer_ ? std::max(0, writer_.matched_readers() - (reader_ ? 1 : 0)) : 0; }
  long TakeAll() override {
    if (!reader_) return 0;
    long n = 0;
    T sample;
    dds::SampleMeta meta;
    while (reader_.TakeNext(sample, meta)) n += meta.valid_data ? 1 : 0;
    return n;
  }

 private:
  dds::Reader<T> reader_;
  dds::Writer<T> writer_;
};

struct Figures {
  int matched_writers = 0;  // the most matched at once, summed over topics
  int matched_readers = 0;
  long samples = 0;
};

void Print(const char* when, const Figures& f, std::size_t refused) {
  std::printf("probe: %smatched_writers=%d matched_readers=%d samples=%ld refused_entities=%zu\n", when,
              f.matched_writers, f.matched_readers, f.samples, refused);
  std::fflush(stdout);
}

int Run(const common::Options& o) {
  const common::SessionOptions where = node::ReadSessionOptions(o);
  const std::string name = o.GetString("as");
  dds::Participant participant(where, name);
  std::vector<std::string> refused;
  std::vector<std::unique_ptr<TopicProbe>> probes;
  namespace t = dds::topics;
  probes.push_back(std::make_unique<TypedProbe<msg::MemberInfo>>(participant, t::kMemberInfo, refused));
  probes.push_back(std::make_unique<TypedProbe<msg::SceneState>>(participant, t::kSceneState, refused));
  probes.push_back(std::make_unique<TypedProbe<msg::MessageBoard>>(participant, t::kMessageBoard, refused));
  probes.push_back(std::make_unique<TypedProbe<msg::DeviceState>>(participant, t::kDeviceState, refused));
  probes.push_back(std::make_unique<TypedProbe<msg::ContactSet>>(participant, t::kContactSet, refused));
  probes.push_back(std::make_unique<TypedProbe<msg::ObjectState>>(participant, t::kObjectState, refused));
  probes.push_back(std::make_unique<TypedProbe<msg::Deformation>>(participant, t::kDeformation, refused));
  probes.push_back(std::make_unique<TypedProbe<msg::ControlEvent>>(participant, t::kControlEvent, refused));
  probes.push_back(std::make_unique<TypedProbe<msg::LoopStatistics>>(participant, t::kLoopStatistics, refused));
  for (const std::string& r : refused) std::printf("probe: own permissions refuse the %s\n", r.c_str());
  std::printf("probe: joined domain %d session '%s' as '%s'%s\n", where.domain_id, where.session.c_str(),
              name.c_str(), where.security_dir.empty() ? " without security" : " with security");
  std::fflush(stdout);

  const auto end = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                          where.duration.count() > 0 ? where.duration
                                                                                     : std::chrono::hours(24));
  Figures seen;
  while (!common::ShutdownRequested() && std::chrono::steady_clock::now() < end) {
    Figures now;
    const long before = seen.samples;
    for (auto& p : probes) {
      now.matched_writers += p->matched_writers();
      now.matched_readers += p->matched_readers();
      seen.samples += p->TakeAll();
    }
    const bool grew = now.matched_writers > seen.matched_writers || now.matched_readers > seen.matched_readers;
    seen.matched_writers = std::max(seen.matched_writers, now.matched_writers);
    seen.matched_readers = std::max(seen.matched_readers, now.matched_readers);
    // Samples: report the first one, then every hundredth.
    if (grew || (before == 0 && seen.samples > 0) || seen.samples / 100 > before / 100) Print("", seen, refused.size());
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  Print("final ", seen, refused.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  handshare::common::Options options(
      "security_probe", "Joins a session and counts the endpoints it matches and the samples it reads (security tests).");
  handshare::node::DeclareSessionOptions(options);
  options.Value("as", "NAME", "participant name; with --security it picks the identity (e.g. haptic_node/bob)",
                "security_probe");
  return handshare::node::RunNodeMain(argc, argv, options, [](const handshare::common::Options& o) { return Run(o); });
}
