#pragma once
/// The thin typed DDS layer: the only code in handshare that includes Fast DDS headers.
///
/// One Participant per process and domain; writers and readers are typed by the generated
/// message types (handshare/idl/handshare.h) and get their QoS from named profiles in
/// deploy/qos/*.xml. Every entity creation is checked and a failure throws DdsError naming
/// the entity, topic and profile. Not real-time: the haptic thread never calls this layer.
#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "handshare/common/session_options.hpp"

namespace handshare::dds {

class DdsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Where the QoS profiles come from: $HANDSHARE_QOS_FILE if set, else the file given here,
/// else handshare_qos.xml in common::QosDir() (installed share/handshare/qos, or the source
/// tree's deploy/qos).
std::string DefaultQosFile();

enum class InstanceState { kAlive, kDisposed, kNoWriters };

/// What a reader learns besides the sample.
struct SampleMeta {
  using Key = std::array<std::uint8_t, 16>;
  bool valid_data = false;        // false: only the instance state changed (leave, lost writer)
  InstanceState instance_state = InstanceState::kAlive;
  std::array<std::uint8_t, 16> instance{};  // key hash: identifies the instance (e.g. a member)
  std::int64_t source_timestamp_ns = 0;     // writer's clock (UTC)
  std::array<std::uint8_t, 16> writer{};    // the writer that sent it (see TakeWriterChange)
};

/// A writer of a reader's topic that went away (unmatched: killed, lost, deleted; or lost its
/// liveliness) or came (matched, or regained liveliness: a new one, or a lost one back after a
/// partition healed), identified as in SampleMeta::writer.
struct WriterChange {
  std::array<std::uint8_t, 16> writer{};
  bool alive = false;  ///< false: went away; true: came or came back
};

/// What one topic carried through one participant, since it was created: samples written
/// (including disposes), samples taken with data, and samples the middleware reports lost on
/// the way in (gaps in a writer's sequence numbers: best-effort samples that did not arrive;
/// samples a keep-last history replaced before they were taken are not counted).
struct TopicTraffic {
  std::string topic;
  std::uint64_t written = 0;
  std::uint64_t written_bytes = 0;  ///< serialized payload of the samples written (CDR, its 4-byte header included)
  std::uint64_t taken = 0;
  std::uint64_t lost = 0;
};

namespace detail {
class TypeHandle;          // a registered type support (defined in the .cpp)
class ParticipantImpl;

/// Type-erased writer/reader: the templates below only cast.
class UntypedWriter {
 public:
  virtual ~UntypedWriter() = default;
  virtual void Write(const void* sample) = 0;
  virtual void Dispose(const void* sample) = 0;
  virtual int matched_readers() const = 0;
  virtual bool WaitForAcknowledgments(std::chrono::nanoseconds timeout) = 0;
};
class UntypedReader {
 public:
  virtual ~UntypedReader() = default;
  virtual bool TakeNext(void* sample, SampleMeta& meta) = 0;
  virtual bool WaitForData(std::chrono::nanoseconds timeout) = 0;
  virtual int matched_writers() const = 0;
  virtual bool TakeWriterChange(WriterChange& change) = 0;
  virtual std::uint64_t deadlines_missed() const = 0;
  virtual void OnDataAvailable(std::function<void()> notify) = 0;
};

/// Defined in types.cpp for every message type of handshare.idl.
template <class T>
struct TypeOf {
  static const char* Name();
  static std::shared_ptr<void> MakeSupport();  // eprosima TypeSupport, type-erased
};
}  // namespace detail

template <class T>
class Writer {
 public:
  Writer() = default;
  explicit Writer(std::unique_ptr<detail::UntypedWriter> w) : w_(std::move(w)) {}
  /// Publishes one sample. Throws DdsError if the middleware refuses it.
  void Write(const T& sample) { w_->Write(&sample); }
  /// Disposes the instance whose key is in sample (keyed topics: a clean leave).
  void Dispose(const T& sample) { w_->Dispose(&sample); }
  /// Readers currently matched: writers of optional streams skip work when this is 0.
  int matched_readers() const { return w_->matched_readers(); }
  /// Blocks until every matched reliable reader acknowledged every sample written so far, or
  /// the timeout passes (false). A reader counts as matched here once the writer has matched
  /// it; with DDS-Security the reader's own side may match later, and it acknowledges only
  /// then, after the transient-local history reached it. True at once for best-effort writers.
  bool WaitForAcknowledgments(std::chrono::nanoseconds timeout) { return w_->WaitForAcknowledgments(timeout); }
  explicit operator bool() const { return w_ != nullptr; }

 private:
  std::unique_ptr<detail::UntypedWriter> w_;
};

template <class T>
class Reader {
 public:
  Reader() = default;
  explicit Reader(std::unique_ptr<detail::UntypedReader> r) : r_(std::move(r)) {}
  /// Takes the next sample if any (non-blocking).
  bool TakeNext(T& sample, SampleMeta& meta) { return r_->TakeNext(&sample, meta); }
  /// Blocks on a WaitSet until data is available or the timeout passes.
  bool WaitForData(std::chrono::nanoseconds timeout) { return r_->WaitForData(timeout); }
  int matched_writers() const { return r_->matched_writers(); }
  /// The next writer change, in the order they happened. Fast DDS 2.9 does not reliably turn a
  /// killed writer into a NOT_ALIVE_NO_WRITERS sample, nor deliver a transient-local sample
  /// again to a reader it re-matches after a partition, so owners track the writers they saw.
  bool TakeWriterChange(WriterChange& change) { return r_->TakeWriterChange(change); }
  /// Requested-deadline misses so far (profiles with a deadline: a writer's instance that sent
  /// nothing for a whole period, counted once per instance and period; 0 without a deadline).
  std::uint64_t deadlines_missed() const { return r_->deadlines_missed(); }
  /// From now on, `notify` runs on the middleware's receive thread whenever samples arrive:
  /// it must only signal (e.g. common::Wakeup::Post) and outlive this reader; the owner takes
  /// the samples on its own thread. Set once; WaitForData is not for such a reader.
  void OnDataAvailable(std::function<void()> notify) { r_->OnDataAvailable(std::move(notify)); }
  explicit operator bool() const { return r_ != nullptr; }

 private:
  std::unique_ptr<detail::UntypedReader> r_;
};

class Participant {
 public:
  /// @param domain_id   DDS domain (0..232).
  /// @param session     the session: publisher and subscriber partition, so sessions on one
  ///                    domain never see each other's samples.
  /// @param name        participant name shown by DDS tools.
  /// @param qos_file    XML profiles; empty: DefaultQosFile().
  /// @param security_dir  DDS-Security keystore; the identity is the enclave of name
  ///                    (EnclaveOf in security.hpp); empty: no security.
  Participant(int domain_id, const std::string& session, const std::string& name,
              const std::string& qos_file = "", const std::string& security_dir = "");
  /// A node's participant from its session options (--domain, --session, --qos, and the
  /// discovery and security options every node shares).
  Participant(const common::SessionOptions& where, const std::string& name);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  /// @param profile  a data_writer profile name of the QoS file, e.g. "state".
  template <class T>
  Writer<T> CreateWriter(const std::string& topic, const std::string& profile) {
    return Writer<T>(CreateUntypedWriter(topic, detail::TypeOf<T>::Name(),
                                         detail::TypeOf<T>::MakeSupport(), profile));
  }
  /// @param profile  a data_reader profile name of the QoS file.
  template <class T>
  Reader<T> CreateReader(const std::string& topic, const std::string& profile) {
    return Reader<T>(CreateUntypedReader(topic, detail::TypeOf<T>::Name(),
                                         detail::TypeOf<T>::MakeSupport(), profile));
  }

  int domain_id() const noexcept { return domain_id_; }
  const std::string& session() const noexcept { return session_; }

  /// Every topic this participant wrote or read, by name.
  std::vector<TopicTraffic> Traffic() const;
  /// Every byte this participant's writers wrote so far (TopicTraffic::written_bytes summed).
  std::uint64_t WrittenBytes() const;
  /// Deadline misses so far (QoS profiles with a deadline): its readers' requested misses (a
  /// writer's instance that sent nothing for a whole period) and its writers' offered misses
  /// counted while a reader was matched (a writer with nobody to read it may fall silent).
  /// Deleted readers and writers keep their share.
  std::uint64_t DeadlinesMissed() const;
  /// One line for a node's exit summary: "traffic: device_state out 3229; contact_set out 120
  /// in 340 lost 2; ..." (topics without the "handshare/" prefix; "none" if nothing moved).
  std::string TrafficSummary() const;

 private:
  std::unique_ptr<detail::UntypedWriter> CreateUntypedWriter(const std::string& topic,
                                                             const char* type_name,
                                                             std::shared_ptr<void> support,
                                                             const std::string& profile);
  std::unique_ptr<detail::UntypedReader> CreateUntypedReader(const std::string& topic,
                                                             const char* type_name,
                                                             std::shared_ptr<void> support,
                                                             const std::string& profile);
  int domain_id_;
  std::string session_;
  std::shared_ptr<detail::ParticipantImpl> impl_;
};

}  // namespace handshare::dds
