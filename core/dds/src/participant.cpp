// Fast DDS lives in core/dds/src only: entities here, types in types.cpp, participant ids and peers in
// discovery.cpp, DDS-Security in security.cpp, a guard for one of its races in lease_race_guard.cpp.
// Every C-style return code and null entity is turned into a DdsError that names what failed.
#include "handshare/dds/participant.hpp"

#include "discovery.hpp"
#include "handshare/common/data_dir.hpp"
#include "edp_heartbeat.hpp"
#include "lease_race_guard.hpp"
#include "security_properties.hpp"

#include <fastdds/dds/core/condition/StatusCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <cstdio>
#include <fastdds/rtps/flowcontrol/FlowControllerDescriptor.hpp>

#include <cstdlib>
#include <deque>
#include <filesystem>
#include <functional>
#include <atomic>
#include <map>
#include <mutex>
#include <set>
#include <vector>

namespace handshare::dds {

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

namespace {

constexpr const char* kParticipantProfile = "handshare_participant";

void Check(const ReturnCode_t& rc, const std::string& what) {
  if (rc != ReturnCode_t::RETCODE_OK) {
    throw DdsError("DDS: " + what + " failed (return code " + std::to_string(rc()) + ")");
  }
}

template <class P>
P* CheckEntity(P* entity, const std::string& what) {
  if (entity == nullptr) throw DdsError("DDS: could not create " + what);
  return entity;
}

// XML profiles are process-wide in Fast DDS: load each file once.
void LoadProfilesOnce(const std::string& file) {
  static std::mutex mutex;
  static std::set<std::string> loaded;
  std::lock_guard<std::mutex> lock(mutex);
  if (loaded.count(file)) return;
  if (!std::filesystem::exists(file)) {
    throw DdsError("DDS: QoS profile file not found: " + file +
                   " (set HANDSHARE_QOS_FILE, or give --qos FILE)");
  }
  Check(fdds::DomainParticipantFactory::get_instance()->load_XML_profiles_file(file),
        "loading QoS profiles from " + file);
  loaded.insert(file);
}

// A property of a QoS profile's propertiesPolicy, or nullptr.
const std::string* FindProperty(const eprosima::fastrtps::rtps::PropertyPolicy& policy, const std::string& name) {
  return eprosima::fastrtps::rtps::PropertyPolicyHelper::find_property(policy, name);
}

long PositiveProperty(const eprosima::fastrtps::rtps::PropertyPolicy& policy, const std::string& name,
                      long max) {
  const std::string* text = FindProperty(policy, name);
  if (text == nullptr) throw DdsError("DDS: participant profile property " + name + " is missing");
  std::size_t used = 0;
  long value = 0;
  try {
    value = std::stol(*text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text->size() || value < 1 || value > max) {
    throw DdsError("DDS: participant profile property " + name + " = '" + *text + "': expected 1.." +
                   std::to_string(max));
  }
  return value;
}

std::int64_t ToNs(const eprosima::fastrtps::rtps::Time_t& t) {
  return static_cast<std::int64_t>(t.seconds()) * 1000000000LL + t.nanosec();
}

}  // namespace

namespace detail {
// One topic's counters, shared by the participant and its endpoints on that topic.
struct TrafficCounters {
  std::atomic<std::uint64_t> written{0};
  std::atomic<std::uint64_t> written_bytes{0};  // serialized payload (CDR with its header)
  std::atomic<std::uint64_t> taken{0};
  std::atomic<std::uint64_t> lost_by_gone_readers{0};  // readers deleted: their last lost count
};

// Deadline misses of every endpoint of one participant (Participant::DeadlinesMissed).
struct DeadlineCounters {
  std::atomic<std::uint64_t> requested{0};
  std::atomic<std::uint64_t> offered_while_matched{0};
};

class ParticipantImpl {
 public:
  fdds::DomainParticipant* participant = nullptr;
  fdds::Publisher* publisher = nullptr;
  fdds::Subscriber* subscriber = nullptr;
  std::map<std::string, fdds::Topic*> topics;
  std::map<std::string, std::shared_ptr<void>> types;  // keeps type supports alive
  std::mutex mutex;  // topics and types are created from any thread
  // The flow controller registered from the participant profile ("" if none); writer QoS
  // points at this string (Fast DDS 2.9 keeps the name as a const char*).
  std::string flow_controller;
  std::map<std::string, std::shared_ptr<TrafficCounters>> traffic;  // by topic, under mutex
  std::map<fdds::DataReader*, std::string> live_readers;            // for their lost counts
  DeadlineCounters deadlines;

  std::shared_ptr<TrafficCounters> CountersFor(const std::string& topic) {
    std::lock_guard<std::mutex> lock(mutex);
    auto& c = traffic[topic];
    if (!c) c = std::make_shared<TrafficCounters>();
    return c;
  }

  // Owned by shared_ptr: every writer and reader holds one, so the DDS participant is deleted
  // only after its last endpoint, whatever order the owners are destroyed in.
  ~ParticipantImpl() {
    if (participant == nullptr) return;
    // Deleting every entity and the participant releases its shared-memory segments.
    participant->delete_contained_entities();
    fdds::DomainParticipantFactory::get_instance()->delete_participant(participant);
  }

  fdds::Topic* TopicFor(const std::string& name, const char* type_name,
                        std::shared_ptr<void> support) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!types.count(type_name)) {
      auto* ts = static_cast<fdds::TypeSupport*>(support.get());
      // Keep wire interop with other DDS implementations (see docs/dds.md).
      (*ts)->auto_fill_type_information(false);
      (*ts)->auto_fill_type_object(false);
      Check(ts->register_type(participant), std::string("registering type ") + type_name);
      types[type_name] = std::move(support);
    }
    if (auto it = topics.find(name); it != topics.end()) return it->second;
    fdds::Topic* topic = CheckEntity(
        participant->create_topic(name, type_name, fdds::TOPIC_QOS_DEFAULT), "topic " + name);
    topics[name] = topic;
    return topic;
  }
};
}  // namespace detail

namespace {

// A writer's offered-deadline misses, counted only while a reader is matched: a stream that
// pauses because nobody reads it (the haptic node's device states) has missed nothing.
class DeadlineWriterListener final : public fdds::DataWriterListener {
 public:
  explicit DeadlineWriterListener(detail::DeadlineCounters& counters) : counters_(counters) {}
  void on_publication_matched(fdds::DataWriter*, const fdds::PublicationMatchedStatus& s) override {
    matched_.store(s.current_count, std::memory_order_relaxed);
  }
  void on_offered_deadline_missed(fdds::DataWriter*, const fdds::OfferedDeadlineMissedStatus& s) override {
    if (matched_.load(std::memory_order_relaxed) > 0 && s.total_count_change > 0) {
      counters_.offered_while_matched.fetch_add(static_cast<std::uint64_t>(s.total_count_change),
                                                std::memory_order_relaxed);
    }
  }

 private:
  detail::DeadlineCounters& counters_;
  std::atomic<int> matched_{0};
};

class WriterImpl final : public detail::UntypedWriter {
 public:
  WriterImpl(std::shared_ptr<detail::ParticipantImpl> owner, fdds::Topic* topic, const fdds::DataWriterQos& qos,
             std::string topic_name)
      : owner_(std::move(owner)),
        listener_(owner_->deadlines),
        w_(CheckEntity(owner_->publisher->create_datawriter(topic, qos, &listener_, kListenerMask),
                       "writer on " + topic_name)),
        topic_(topic->get_name()),
        counters_(owner_->CountersFor(topic_)),
        type_(w_->get_type()) {}
  ~WriterImpl() override {
    w_->set_listener(nullptr);
    owner_->publisher->delete_datawriter(w_);
  }
  void Write(const void* sample) override {
    if (!w_->write(const_cast<void*>(sample))) throw DdsError("DDS: write on " + topic_ + " failed");
    counters_->written.fetch_add(1, std::memory_order_relaxed);
    // The payload each matched reader is sent (RTPS, UDP and IP headers come on top).
    counters_->written_bytes.fetch_add(type_.get_serialized_size_provider(const_cast<void*>(sample))(),
                                       std::memory_order_relaxed);
  }
  void Dispose(const void* sample) override {
    Check(w_->dispose(const_cast<void*>(sample), fdds::HANDLE_NIL), "dispose on " + topic_);
    counters_->written.fetch_add(1, std::memory_order_relaxed);
    // A dispose usually precedes deleting the writer: give reliable readers up to 0.5 s to
    // acknowledge it, so a clean leave is not mistaken for a lost member.
    w_->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(0, 500000000));
  }
  int matched_readers() const override {
    fdds::PublicationMatchedStatus status;
    Check(w_->get_publication_matched_status(status), "matched status of " + topic_);
    return status.current_count;
  }
  bool WaitForAcknowledgments(std::chrono::nanoseconds timeout) override {
    const auto s = std::chrono::duration_cast<std::chrono::seconds>(timeout);
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(timeout - s);
    return w_->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(static_cast<std::int32_t>(s.count()),
                                                                       static_cast<std::uint32_t>(ns.count()))) ==
           ReturnCode_t::RETCODE_OK;
  }

 private:
  static inline const fdds::StatusMask kListenerMask = fdds::StatusMask::publication_matched()
                                                     << fdds::StatusMask::offered_deadline_missed();
  std::shared_ptr<detail::ParticipantImpl> owner_;
  DeadlineWriterListener listener_;
  fdds::DataWriter* w_;
  std::string topic_;
  std::shared_ptr<detail::TrafficCounters> counters_;
  fdds::TypeSupport type_;
};

// Writers that went away (unmatched: killed, lost, or deleted) or lost liveliness, and writers
// that matched or regained liveliness (a partition healed). The listener only records them;
// the reader's owner takes them on its own thread.
class LostWriterListener final : public fdds::DataReaderListener {
 public:
  explicit LostWriterListener(detail::DeadlineCounters& counters) : counters_(counters) {}
  void on_subscription_matched(fdds::DataReader*, const fdds::SubscriptionMatchedStatus& s) override {
    if (s.current_count_change < 0) Push(false, s.last_publication_handle);
    if (s.current_count_change > 0) Push(true, s.last_publication_handle);
  }
  void on_liveliness_changed(fdds::DataReader*, const fdds::LivelinessChangedStatus& s) override {
    if (s.not_alive_count_change > 0) Push(false, s.last_publication_handle);
    if (s.alive_count_change > 0) Push(true, s.last_publication_handle);
  }
  void on_requested_deadline_missed(fdds::DataReader*, const fdds::RequestedDeadlineMissedStatus& s) override {
    deadlines_missed_.store(static_cast<std::uint64_t>(s.total_count), std::memory_order_relaxed);
    if (s.total_count_change > 0) {
      counters_.requested.fetch_add(static_cast<std::uint64_t>(s.total_count_change), std::memory_order_relaxed);
    }
  }
  std::uint64_t deadlines_missed() const { return deadlines_missed_.load(std::memory_order_relaxed); }
  // A reader whose owner waits on its own wake-up (Reader::OnDataAvailable): only signal.
  void on_data_available(fdds::DataReader*) override {
    if (notify_) notify_();
  }
  void set_notify(std::function<void()> notify) { notify_ = std::move(notify); }
  // In the order they happened (a flapping link: lost, back, lost).
  bool Take(WriterChange& out) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (changes_.empty()) return false;
    out = changes_.front();
    changes_.pop_front();
    return true;
  }

 private:
  void Push(bool alive, const fdds::InstanceHandle_t& h) {
    WriterChange c;
    c.alive = alive;
    for (std::size_t i = 0; i < c.writer.size(); ++i) c.writer[i] = h.value[i];
    std::lock_guard<std::mutex> lock(mutex_);
    changes_.push_back(c);
  }
  detail::DeadlineCounters& counters_;
  std::mutex mutex_;
  std::deque<WriterChange> changes_;
  std::atomic<std::uint64_t> deadlines_missed_{0};
  std::function<void()> notify_;  // set before data_available is in the listener's mask
};

class ReaderImpl final : public detail::UntypedReader {
 public:
  ReaderImpl(std::shared_ptr<detail::ParticipantImpl> owner, fdds::Topic* topic,
             const fdds::DataReaderQos& qos, std::string topic_name)
      : owner_(std::move(owner)),
        topic_(std::move(topic_name)),
        counters_(owner_->CountersFor(topic->get_name())),
        listener_(owner_->deadlines) {
    r_ = CheckEntity(owner_->subscriber->create_datareader(topic, qos, &listener_, kListenerMask),
                     "reader on " + topic_);
    fdds::StatusCondition& condition = r_->get_statuscondition();
    Check(condition.set_enabled_statuses(fdds::StatusMask::data_available()),
          "status mask of " + topic_);
    Check(waitset_.attach_condition(condition), "attaching wait set of " + topic_);
    std::lock_guard<std::mutex> lock(owner_->mutex);
    owner_->live_readers[r_] = topic->get_name();
  }
  ~ReaderImpl() override {
    {
      std::lock_guard<std::mutex> lock(owner_->mutex);
      owner_->live_readers.erase(r_);
      fdds::SampleLostStatus lost;
      if (r_->get_sample_lost_status(lost) == ReturnCode_t::RETCODE_OK && lost.total_count > 0) {
        counters_->lost_by_gone_readers.fetch_add(static_cast<std::uint64_t>(lost.total_count));
      }
    }
    waitset_.detach_condition(r_->get_statuscondition());
    r_->set_listener(nullptr);
    owner_->subscriber->delete_datareader(r_);
  }

  bool TakeWriterChange(WriterChange& change) override { return listener_.Take(change); }
  void OnDataAvailable(std::function<void()> notify) override {
    listener_.set_notify(std::move(notify));
    fdds::StatusMask mask = kListenerMask;
    mask << fdds::StatusMask::data_available();
    Check(r_->set_listener(&listener_, mask), "data listener of " + topic_);
  }
  std::uint64_t deadlines_missed() const override { return listener_.deadlines_missed(); }

  bool TakeNext(void* sample, SampleMeta& meta) override {
    fdds::SampleInfo info;
    const ReturnCode_t rc = r_->take_next_sample(sample, &info);
    if (rc == ReturnCode_t::RETCODE_NO_DATA) return false;
    Check(rc, "take on " + topic_);
    meta.valid_data = info.valid_data;
    if (info.valid_data) counters_->taken.fetch_add(1, std::memory_order_relaxed);
    switch (info.instance_state) {
      case fdds::NOT_ALIVE_DISPOSED_INSTANCE_STATE:
        meta.instance_state = InstanceState::kDisposed;
        break;
      case fdds::NOT_ALIVE_NO_WRITERS_INSTANCE_STATE:
        meta.instance_state = InstanceState::kNoWriters;
        break;
      default:
        meta.instance_state = InstanceState::kAlive;
    }
    const auto& handle = info.instance_handle.value;
    for (std::size_t i = 0; i < meta.instance.size(); ++i) meta.instance[i] = handle[i];
    meta.source_timestamp_ns = ToNs(info.source_timestamp);
    const auto& writer = info.publication_handle.value;
    for (std::size_t i = 0; i < meta.writer.size(); ++i) meta.writer[i] = writer[i];
    return true;
  }

  bool WaitForData(std::chrono::nanoseconds timeout) override {
    fdds::ConditionSeq active;
    const auto s = std::chrono::duration_cast<std::chrono::seconds>(timeout);
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(timeout - s);
    const ReturnCode_t rc = waitset_.wait(
        active, eprosima::fastrtps::Duration_t(static_cast<std::int32_t>(s.count()),
                                               static_cast<std::uint32_t>(ns.count())));
    if (rc == ReturnCode_t::RETCODE_TIMEOUT) return false;
    Check(rc, "wait on " + topic_);
    return !active.empty();
  }

  int matched_writers() const override {
    fdds::SubscriptionMatchedStatus status;
    Check(r_->get_subscription_matched_status(status), "matched status of " + topic_);
    return status.current_count;
  }

 private:
  std::shared_ptr<detail::ParticipantImpl> owner_;
  std::string topic_;
  std::shared_ptr<detail::TrafficCounters> counters_;
  static inline const fdds::StatusMask kListenerMask = fdds::StatusMask::subscription_matched()
                                                     << fdds::StatusMask::liveliness_changed()
                                                     << fdds::StatusMask::requested_deadline_missed();
  LostWriterListener listener_;
  fdds::DataReader* r_ = nullptr;
  fdds::WaitSet waitset_;
};

}  // namespace

std::string DefaultQosFile() {
  if (const char* env = std::getenv("HANDSHARE_QOS_FILE"); env != nullptr && *env != '\0') {
    return env;
  }
  return (common::QosDir() / "handshare_qos.xml").string();
}


Participant::Participant(int domain_id, const std::string& session, const std::string& name,
                         const std::string& qos_file, const std::string& security_dir)
    : Participant(
          [&] {
            common::SessionOptions where;
            where.domain_id = domain_id;
            where.session = session;
            where.qos_file = qos_file;
            where.security_dir = security_dir;
            return where;
          }(),
          name) {}

Participant::Participant(const common::SessionOptions& where, const std::string& name)
    : domain_id_(where.domain_id), session_(where.session), impl_(std::make_shared<detail::ParticipantImpl>()) {
  const int domain_id = where.domain_id;
  const std::string& session = where.session;
  const std::string& qos_file = where.qos_file;
  if (domain_id < 0 || domain_id > 232) {
    throw DdsError("DDS: domain id " + std::to_string(domain_id) + " is outside 0..232");
  }
  if (session.empty()) throw DdsError("DDS: session name is empty");
  const std::string file = qos_file.empty() ? DefaultQosFile() : qos_file;
  LoadProfilesOnce(file);

  // The executable's definitions in place of Fast DDS's (library_override.hpp): said once when absent.
  static const bool overrides_checked = [] {
    if (!detail::LeaseRaceGuardActive()) {
      std::fprintf(stderr, "handshare: warning: the guard against Fast DDS's lease-check race is not in effect "
                           "(this executable does not export ParticipantProxyData::clear): a peer leaving may "
                           "abort this process\n");
    }
    if (!detail::EdpHeartbeatShortened()) {
      std::fprintf(stderr, "handshare: warning: Fast DDS's endpoint discovery keeps its 1 s heartbeat (this "
                           "executable does not export EDPSimple::set_builtin_writer_attributes): a lost discovery "
                           "datagram may delay a match by a second\n");
    }
    return true;
  }();
  (void)overrides_checked;
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  fdds::DomainParticipantQos pqos;
  Check(factory->get_participant_qos_from_profile(kParticipantProfile, pqos),
        std::string("reading participant profile '") + kParticipantProfile + "' from " + file);
  pqos.name(name);
  // Flow controllers cannot be given in Fast DDS 2.9 XML: the profile's properties describe one.
  if (const std::string* fc = FindProperty(pqos.properties(), "handshare.flow_controller.name")) {
    impl_->flow_controller = *fc;
    auto descriptor = std::make_shared<eprosima::fastdds::rtps::FlowControllerDescriptor>();
    descriptor->name = impl_->flow_controller.c_str();
    descriptor->scheduler = eprosima::fastdds::rtps::FlowControllerSchedulerPolicy::FIFO;
    descriptor->max_bytes_per_period = static_cast<std::int32_t>(
        PositiveProperty(pqos.properties(), "handshare.flow_controller.max_bytes_per_period", 2147483647L));
    descriptor->period_ms = static_cast<std::uint64_t>(
        PositiveProperty(pqos.properties(), "handshare.flow_controller.period_ms", 60000L));
    pqos.flow_controllers().push_back(descriptor);
  }
  // The identity first: security decides what the participant may announce (security.cpp).
  if (!where.security_dir.empty()) detail::ApplySecurity(where.security_dir, name, pqos);
  detail::ConfigureDiscovery(where, pqos);  // participant id, --peers (discovery.cpp)
  impl_->participant = CheckEntity(factory->create_participant(domain_id, pqos),
                                   "participant '" + name + "' on domain " +
                                       std::to_string(domain_id) + detail::SecurityFailureHint(where.security_dir, name));
  // The session is the partition: sessions sharing a domain never exchange samples.
  fdds::PublisherQos pub_qos = fdds::PUBLISHER_QOS_DEFAULT;
  pub_qos.partition().push_back(session.c_str());
  impl_->publisher = CheckEntity(impl_->participant->create_publisher(pub_qos), "publisher");
  fdds::SubscriberQos sub_qos = fdds::SUBSCRIBER_QOS_DEFAULT;
  sub_qos.partition().push_back(session.c_str());
  impl_->subscriber = CheckEntity(impl_->participant->create_subscriber(sub_qos), "subscriber");
}

Participant::~Participant() = default;

std::unique_ptr<detail::UntypedWriter> Participant::CreateUntypedWriter(
    const std::string& topic, const char* type_name, std::shared_ptr<void> support,
    const std::string& profile) {
  fdds::Topic* t = impl_->TopicFor(topic, type_name, std::move(support));
  fdds::DataWriterQos qos;
  Check(impl_->publisher->get_datawriter_qos_from_profile(profile, qos),
        "reading data_writer profile '" + profile + "'");
  // A writer profile names its flow controller in a property (2.9 XML cannot): it must be the
  // participant's, and the writer asynchronous.
  if (const std::string* fc = FindProperty(qos.properties(), "handshare.flow_controller")) {
    if (*fc != impl_->flow_controller) {
      throw DdsError("DDS: data_writer profile '" + profile + "' names flow controller '" + *fc +
                     "', but the participant profile defines " +
                     (impl_->flow_controller.empty() ? std::string("none") : "'" + impl_->flow_controller + "'"));
    }
    if (qos.publish_mode().kind != fdds::ASYNCHRONOUS_PUBLISH_MODE) {
      throw DdsError("DDS: data_writer profile '" + profile + "' has a flow controller but is not ASYNCHRONOUS");
    }
    qos.publish_mode().flow_controller_name = impl_->flow_controller.c_str();
  }
  return std::make_unique<WriterImpl>(impl_, t, qos, topic + " (profile " + profile + ")");
}

std::uint64_t Participant::WrittenBytes() const {
  std::uint64_t bytes = 0;
  std::lock_guard<std::mutex> lock(impl_->mutex);
  for (const auto& [topic, c] : impl_->traffic) bytes += c->written_bytes.load(std::memory_order_relaxed);
  return bytes;
}

std::uint64_t Participant::DeadlinesMissed() const {
  return impl_->deadlines.requested.load(std::memory_order_relaxed) +
         impl_->deadlines.offered_while_matched.load(std::memory_order_relaxed);
}

std::vector<TopicTraffic> Participant::Traffic() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  std::map<std::string, std::uint64_t> live_lost;
  for (const auto& [reader, topic] : impl_->live_readers) {
    fdds::SampleLostStatus lost;
    if (reader->get_sample_lost_status(lost) == ReturnCode_t::RETCODE_OK && lost.total_count > 0) {
      live_lost[topic] += static_cast<std::uint64_t>(lost.total_count);
    }
  }
  std::vector<TopicTraffic> out;
  for (const auto& [topic, c] : impl_->traffic) {
    TopicTraffic t;
    t.topic = topic;
    t.written = c->written.load(std::memory_order_relaxed);
    t.written_bytes = c->written_bytes.load(std::memory_order_relaxed);
    t.taken = c->taken.load(std::memory_order_relaxed);
    t.lost = c->lost_by_gone_readers.load() + live_lost[topic];
    out.push_back(std::move(t));
  }
  return out;
}

std::string Participant::TrafficSummary() const {
  std::string line = "traffic:";
  const char* sep = " ";
  for (const TopicTraffic& t : Traffic()) {
    if (t.written == 0 && t.taken == 0 && t.lost == 0) continue;
    std::string name = t.topic;
    if (name.rfind("handshare/", 0) == 0) name.erase(0, 10);
    line += sep + name;
    if (t.written > 0) {
      char kb[32];
      std::snprintf(kb, sizeof kb, " (%.1f kB)", 1e-3 * static_cast<double>(t.written_bytes));
      line += " out " + std::to_string(t.written) + kb;
    }
    if (t.taken > 0 || t.lost > 0) line += " in " + std::to_string(t.taken);
    if (t.lost > 0) line += " lost " + std::to_string(t.lost);
    sep = "; ";
  }
  return std::string(sep) == " " ? line + " none" : line;
}

std::unique_ptr<detail::UntypedReader> Participant::CreateUntypedReader(
    const std::string& topic, const char* type_name, std::shared_ptr<void> support,
    const std::string& profile) {
  fdds::Topic* t = impl_->TopicFor(topic, type_name, std::move(support));
  fdds::DataReaderQos qos;
  Check(impl_->subscriber->get_datareader_qos_from_profile(profile, qos),
        "reading data_reader profile '" + profile + "'");
  return std::make_unique<ReaderImpl>(impl_, t, qos, topic + " (profile " + profile + ")");
}

}  // namespace handshare::dds
