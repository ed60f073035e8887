#include "handshare/world_server/recording.hpp"

#include <unistd.h>

#include <algorithm>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "handshare/common/clock.hpp"
#include "handshare/node/rejoin_clock.hpp"
#include "handshare/dds/roster_rejoin.hpp"
#include "handshare/common/shutdown.hpp"
#include "handshare/dds/membership.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/dds/sample_checks.hpp"
#include "handshare/dds/serialization.hpp"
#include "handshare/world_server/member_registry.hpp"
#include "handshare/world_server/session_log.hpp"
#include "server_conversions.hpp"
#include "sqlite_db.hpp"

namespace handshare::server {
namespace {

using SteadyClock = std::chrono::steady_clock;

// The recording's own tables, next to the session log's (one transaction, one file).
constexpr const char* kCreateRecording = R"sql(
CREATE TABLE recording(
  id              INTEGER PRIMARY KEY CHECK (id = 1),
  format_version  INTEGER NOT NULL,
  session         TEXT    NOT NULL,
  domain_id       INTEGER NOT NULL,
  log_session_id  INTEGER NOT NULL,            -- its row in sessions (the rebuilt session log)
  started_unix_ns INTEGER NOT NULL,
  ended_unix_ns   INTEGER,                     -- NULL: the recorder did not end cleanly
  samples         INTEGER NOT NULL DEFAULT 0,
  dropped         INTEGER NOT NULL DEFAULT 0
);
CREATE TABLE instances(
  id    INTEGER PRIMARY KEY,
  topic TEXT NOT NULL,
  key   BLOB NOT NULL                          -- the 16-byte DDS key hash
);
CREATE TABLE samples(
  id        INTEGER PRIMARY KEY,               -- order of reception
  steady_ns INTEGER NOT NULL,                  -- since started (recorder's steady clock)
  unix_ns   INTEGER NOT NULL,
  instance  INTEGER NOT NULL REFERENCES instances(id),
  state     INTEGER NOT NULL,                  -- 0 alive, 1 disposed, 2 no writers, 3 writer lost
  cdr       BLOB    NOT NULL                   -- the sample as on the wire (CDR, encapsulation first)
);
)sql";

std::string Where(const std::filesystem::path& file) { return file.string(); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// Writer: SessionLog creates the file (the session log's schema and its session row); this
// connection adds the recording's tables and inserts the samples on its own thread.
namespace detail {
class RecordingWriterImpl {
 public:
  RecordingWriterImpl(const std::filesystem::path& file, const SessionStart& start, std::chrono::milliseconds flush)
      : log_(file, start, SessionLogConfig{flush}), db_(file, SQLITE_OPEN_READWRITE), flush_(flush) {
    db_.Check(sqlite3_busy_timeout(db_.get(), 5000), "setting the busy timeout");
    db_.Exec("PRAGMA synchronous=NORMAL", "setting synchronous=NORMAL");
    db_.Exec("BEGIN IMMEDIATE", "starting the recording's schema");
    db_.Exec(kCreateRecording, "creating the recording's tables");
    sqlite::Statement info(db_,
                           "INSERT INTO recording(id, format_version, session, domain_id, log_session_id, "
                           "started_unix_ns) VALUES (1, ?1, ?2, ?3, ?4, ?5)",
                           "writing the recording's header");
    info.Bind(1, std::int64_t{RecordingReader::kFormatVersion}).Bind(2, start.name)
        .Bind(3, std::int64_t{start.domain_id}).Bind(4, log_.session_id())
        .Bind(5, static_cast<std::int64_t>(start.unix_ns));
    info.Step();
    db_.Exec("COMMIT", "committing the recording's schema");
    thread_ = std::thread([this] { Loop(); });
  }
  ~RecordingWriterImpl() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

  SessionLog& log() { return log_; }

  void Push(RecordedSample s) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.size() >= kMaxQueued) {
      ++dropped_;
      return;
    }
    queue_.push_back(std::move(s));
  }
  /// Commits what is queued and writes the end; throws the writer thread's error if any.
  void Finish(std::int64_t ended_unix_ns) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
    if (!error_.empty()) throw RecordingError(error_);
    sqlite::Statement end(db_, "UPDATE recording SET ended_unix_ns = ?1, samples = ?2, dropped = ?3 WHERE id = 1",
                          "writing the recording's end");
    end.Bind(1, ended_unix_ns).Bind(2, written_).Bind(3, static_cast<std::int64_t>(dropped_));
    end.Step();
    log_.End(static_cast<std::uint64_t>(ended_unix_ns));
    log_.Flush();
  }
  std::int64_t written() const { return written_; }

 private:
  static constexpr std::size_t kMaxQueued = 200000;

  void Loop() {
    sqlite::Statement insert(db_, "INSERT INTO samples(steady_ns, unix_ns, instance, state, cdr) VALUES (?1, ?2, ?3, ?4, ?5)",
                             "inserting a sample");
    sqlite::Statement add_instance(db_, "INSERT INTO instances(topic, key) VALUES (?1, ?2)", "inserting an instance");
    std::map<std::pair<std::string, std::array<std::uint8_t, 16>>, std::int64_t> instances;
    std::vector<RecordedSample> batch;
    for (;;) {
      bool stopping;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait_for(lock, flush_, [&] { return stop_; });
        batch.swap(queue_);
        stopping = stop_;
      }
      if (!batch.empty() && error_.empty()) {
        try {
          db_.Exec("BEGIN IMMEDIATE", "starting a batch of samples");
          for (const auto& s : batch) {
            auto [it, added] = instances.try_emplace({s.topic, s.instance}, 0);
            if (added) {
              add_instance.Bind(1, s.topic).BindBlob(2, s.instance);
              add_instance.Step();
              add_instance.Reset();
              it->second = sqlite3_last_insert_rowid(db_.get());
            }
            insert.Bind(1, s.steady_ns).Bind(2, s.unix_ns).Bind(3, it->second)
                .Bind(4, static_cast<std::int64_t>(s.state)).BindBlob(5, s.cdr);
            insert.Step();
            insert.Reset();
          }
          db_.Exec("COMMIT", "committing a batch of samples");
          written_ += static_cast<std::int64_t>(batch.size());
        } catch (const std::exception& e) {
          sqlite3_exec(db_.get(), "ROLLBACK", nullptr, nullptr, nullptr);
          error_ = e.what();
        }
      }
      batch.clear();
      if (stopping) return;
    }
  }

  SessionLog log_;
  sqlite::Db db_;
  std::chrono::milliseconds flush_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<RecordedSample> queue_;
  bool stop_ = false;
  std::uint64_t dropped_ = 0;
  std::int64_t written_ = 0;  // writer thread only (read after join)
  std::string error_;         // writer thread only (read after join)
  std::thread thread_;
};
}  // namespace detail

RecordingWriter::RecordingWriter(const std::filesystem::path& file, const SessionStart& start,
                                 std::chrono::milliseconds flush_period) {
  if (std::filesystem::exists(file)) {
    throw RecordingError(file.string() + ": already exists (a recording is never overwritten or appended to)");
  }
  try {
    impl_ = std::make_unique<detail::RecordingWriterImpl>(file, start, flush_period);
  } catch (const SessionLogError& e) {
    throw RecordingError(e.what());
  }
}
RecordingWriter::~RecordingWriter() = default;
void RecordingWriter::Push(RecordedSample sample) { impl_->Push(std::move(sample)); }
void RecordingWriter::Finish(std::int64_t ended_unix_ns) {
  try {
    impl_->Finish(ended_unix_ns);
  } catch (const SessionLogError& e) {
    throw RecordingError(e.what());
  }
}
SessionLog& RecordingWriter::log() { return impl_->log(); }
std::int64_t RecordingWriter::written() const { return impl_->written(); }

namespace {

// A file SQLite would call "malformed" somewhere later: say where it is cut, from its header.
void CheckFileHeader(const std::filesystem::path& file) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  if (ec) throw RecordingError(Where(file) + ": cannot read the recording: " + ec.message());
  std::ifstream in(file, std::ios::binary);
  unsigned char h[100] = {};
  in.read(reinterpret_cast<char*>(h), sizeof h);
  if (size < 100 || !in) {
    throw RecordingError(Where(file) + ": truncated at byte " + std::to_string(size) +
                         ": shorter than SQLite's 100-byte header");
  }
  if (std::string(reinterpret_cast<const char*>(h), 16) != std::string("SQLite format 3\0", 16)) {
    throw RecordingError(Where(file) + ": not a recording (no SQLite header at byte 0)");
  }
  const auto be32 = [&](int at) {
    return (std::uint64_t{h[at]} << 24) | (std::uint64_t{h[at + 1]} << 16) | (std::uint64_t{h[at + 2]} << 8) | h[at + 3];
  };
  std::uint64_t page_size = (std::uint64_t{h[16]} << 8) | h[17];
  if (page_size == 1) page_size = 65536;
  const std::uint64_t pages = be32(28);
  // The header's page count is valid when its change counter matches (SQLite file format 1.3.8).
  const bool count_valid = pages > 0 && be32(24) == be32(92);
  std::filesystem::path wal = file;
  wal += "-wal";
  if (count_valid && !std::filesystem::exists(wal) && size < pages * page_size) {
    throw RecordingError(Where(file) + ": truncated at byte " + std::to_string(size) + " (page " +
                         std::to_string(size / page_size + 1) + "): its header says " + std::to_string(pages) +
                         " pages of " + std::to_string(page_size) + " bytes = " +
                         std::to_string(pages * page_size) + " bytes");
  }
}

}  // namespace

const std::vector<std::string>& RecordedTopics() {
  namespace t = dds::topics;
  static const std::vector<std::string> names{t::kMemberInfo.name, t::kSceneState.name,  t::kMessageBoard.name,
                                              t::kDeviceState.name, t::kContactSet.name, t::kObjectState.name,
                                              t::kDeformation.name, t::kControlEvent.name, t::kLoopStatistics.name,
                                              t::kControlState.name};
  return names;
}

// ---------------------------------------------------------------------------------------------
// Reader

struct RecordingReader::Impl {
  explicit Impl(const std::filesystem::path& file) : db(file, SQLITE_OPEN_READONLY) {}
  sqlite::Db db;
  std::optional<sqlite::Statement> rows;
};

RecordingReader::RecordingReader(const std::filesystem::path& file) : file_(file) {
  if (!std::filesystem::exists(file)) throw RecordingError(Where(file) + ": no such recording");
  CheckFileHeader(file);
  try {
    impl_ = std::make_unique<Impl>(file);
    sqlite::Db& db = impl_->db;
    db.Check(sqlite3_busy_timeout(db.get(), 2000), "setting the busy timeout");
    if (db.QueryInt("SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = 'recording'",
                    "looking for the recording table") == 0) {
      throw RecordingError(Where(file) + ": not a recording (no table 'recording'; a session log? read it with "
                                         "session_report)");
    }
    sqlite::Statement s(db,
                        "SELECT format_version, session, domain_id, started_unix_ns, ended_unix_ns, dropped, "
                        "(SELECT count(*) FROM samples) FROM recording WHERE id = 1",
                        "reading the recording's header");
    if (!s.Step()) throw RecordingError(Where(file) + ": the recording has no header row");
    info_.format_version = static_cast<int>(s.Int(0));
    info_.session = s.Text(1);
    info_.domain_id = static_cast<int>(s.Int(2));
    info_.started_unix_ns = s.Int(3);
    info_.ended_unix_ns = s.IsNull(4) ? 0 : s.Int(4);
    info_.dropped = s.Int(5);
    info_.samples = s.Int(6);
    if (info_.format_version > kFormatVersion) {
      throw RecordingError(Where(file) + ": recording format " + std::to_string(info_.format_version) +
                           " is newer than this build's (" + std::to_string(kFormatVersion) + ")");
    }
    impl_->rows.emplace(db,
                        "SELECT s.id, s.steady_ns, s.unix_ns, i.topic, i.key, s.state, s.cdr "
                        "FROM samples s JOIN instances i ON i.id = s.instance ORDER BY s.id",
                        "reading the samples");
  } catch (const SessionLogError& e) {
    throw RecordingError(e.what());
  }
}

RecordingReader::~RecordingReader() = default;

bool RecordingReader::Next(RecordedSample& sample) {
  try {
    sqlite::Statement& r = *impl_->rows;
    if (!r.Step()) return false;
    sample.id = r.Int(0);
    sample.steady_ns = r.Int(1);
    sample.unix_ns = r.Int(2);
    sample.topic = r.Text(3);
    const auto key = r.Blob(4);
    sample.instance.fill(0);
    for (std::size_t i = 0; i < key.size() && i < sample.instance.size(); ++i) sample.instance[i] = key[i];
    const auto state = r.Int(5);
    if (state < 0 || state > 3) {
      throw RecordingError(Where(file_) + ": sample #" + std::to_string(sample.id) + " (topic " + sample.topic +
                           "): unknown instance state " + std::to_string(state));
    }
    sample.state = static_cast<RecordedState>(state);
    sample.cdr = r.Blob(6);
    last_id_ = sample.id;
    return true;
  } catch (const SessionLogError& e) {
    // SQLite's message names the file and says what (e.g. "database disk image is malformed").
    throw RecordingError(std::string(e.what()) + " (after sample #" + std::to_string(last_id_) + " of " +
                         std::to_string(info_.samples) + ")");
  }
}

namespace {

// LoopStatistics gained deadline_misses and sent_bytes_per_s (an 8-byte count and an 8-byte
// rate appended to a @final XCDR1 type, session log schema 5): a sample recorded before ends
// 16 bytes early, right after samples_dropped (8-aligned: no padding), and reads with both 0.
msg::LoopStatistics DeserializeLoopStatistics(std::span<const std::uint8_t> cdr) {
  msg::LoopStatistics sample;
  try {
    dds::Deserialize(cdr, sample);
    return sample;
  } catch (const dds::SerializationError&) {
    std::vector<std::uint8_t> padded(cdr.begin(), cdr.end());
    padded.resize(padded.size() + 16, 0);
    try {
      dds::Deserialize(padded, sample);
      return sample;
    } catch (const dds::SerializationError&) {
    }
    throw;  // not an older sample either: where the payload as recorded stops
  }
}

// Calls f(msg::T&) with the sample of `topic` deserialized; false for an unknown topic.
template <class F>
bool WithSample(const RecordedSample& s, F&& f) {
  namespace t = dds::topics;
  const auto as = [&]<class T>(T sample) {
    dds::Deserialize(s.cdr, sample);
    f(sample);
    return true;
  };
  if (s.topic == t::kMemberInfo.name) return as(msg::MemberInfo{});
  if (s.topic == t::kSceneState.name) return as(msg::SceneState{});
  if (s.topic == t::kMessageBoard.name) return as(msg::MessageBoard{});
  if (s.topic == t::kDeviceState.name) return as(msg::DeviceState{});
  if (s.topic == t::kContactSet.name) return as(msg::ContactSet{});
  if (s.topic == t::kObjectState.name) return as(msg::ObjectState{});
  if (s.topic == t::kDeformation.name) return as(msg::Deformation{});
  if (s.topic == t::kControlEvent.name) return as(msg::ControlEvent{});
  if (s.topic == t::kLoopStatistics.name) {
    msg::LoopStatistics sample = DeserializeLoopStatistics(s.cdr);
    f(sample);
    return true;
  }
  if (s.topic == t::kControlState.name) return as(msg::ControlState{});
  return false;
}

// Deserializes one sample and hands it to f; a bad one throws naming file, sample and offset.
template <class F>
void Decode(const std::filesystem::path& file, const RecordedSample& s, F&& f) {
  if (s.cdr.empty()) return;  // a dispose of an instance whose sample was never received
  try {
    if (!WithSample(s, f)) {
      throw RecordingError(Where(file) + ": sample #" + std::to_string(s.id) + ": unknown topic '" + s.topic + "'");
    }
  } catch (const dds::SerializationError& e) {
    throw RecordingError(Where(file) + ": sample #" + std::to_string(s.id) + " (topic " + s.topic + ", offset " +
                         std::to_string(e.offset()) + " bytes into its payload): " + e.what());
  }
}

}  // namespace

std::int64_t VerifyRecording(const std::filesystem::path& file) {
  RecordingReader reader(file);
  RecordedSample s;
  std::int64_t n = 0;
  while (reader.Next(s)) {
    Decode(file, s, [](const auto&) {});
    ++n;
  }
  return n;
}

// ---------------------------------------------------------------------------------------------
// Recorder

namespace {

class TopicTap {
 public:
  virtual ~TopicTap() = default;
  /// Takes what arrived; returns samples queued.
  virtual int Drain(RecordingWriter& out, std::int64_t t0_steady_ns) = 0;
};

std::int64_t SteadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(SteadyClock::now().time_since_epoch()).count();
}

template <class T>
class Tap : public TopicTap {
 public:
  using OnSample = std::function<void(const T&, const dds::SampleMeta&, std::int64_t unix_ns)>;
  using OnLost = std::function<void(const dds::SampleMeta::Key&, std::int64_t unix_ns)>;
  Tap(dds::Participant& p, const dds::topics::TopicSpec& spec, OnSample on_sample = {}, OnLost on_lost = {})
      : topic_(spec.name), reader_(dds::MakeReader<T>(p, spec)), on_sample_(std::move(on_sample)),
        on_lost_(std::move(on_lost)) {}

  int Drain(RecordingWriter& out, std::int64_t t0) override {
    int n = 0;
    dds::SampleMeta meta;
    while (reader_.TakeNext(sample_, meta)) {
      RecordedSample r;
      r.steady_ns = SteadyNs() - t0;
      r.unix_ns = static_cast<std::int64_t>(common::UnixNowNs());
      r.topic = topic_;
      r.instance = meta.instance;
      Instance& inst = instances_[meta.instance];
      if (meta.valid_data) {
        r.cdr = dds::Serialize(sample_);
        inst.last = r.cdr;
        inst.writer = meta.writer;
        r.state = RecordedState::kAlive;
      } else {
        // Only the instance state changed: the instance's last sample carries its key.
        r.cdr = inst.last;
        r.state = meta.instance_state == dds::InstanceState::kDisposed ? RecordedState::kDisposed
                                                                       : RecordedState::kNoWriters;
      }
      if (on_sample_) on_sample_(sample_, meta, r.unix_ns);
      out.Push(std::move(r));
      ++n;
    }
    dds::WriterChange change;
    while (reader_.TakeWriterChange(change)) {
      if (change.alive) continue;  // a writer coming back brings its samples itself
      const auto& lost = change.writer;
      const auto unix_ns = static_cast<std::int64_t>(common::UnixNowNs());
      for (const auto& [key, inst] : instances_) {
        if (inst.writer != lost || inst.last.empty()) continue;
        RecordedSample r;
        r.steady_ns = SteadyNs() - t0;
        r.unix_ns = unix_ns;
        r.topic = topic_;
        r.instance = key;
        r.state = RecordedState::kWriterLost;
        r.cdr = inst.last;
        out.Push(std::move(r));
        ++n;
      }
      if (on_lost_) on_lost_(lost, unix_ns);
    }
    return n;
  }

 private:
  struct Instance {
    std::vector<std::uint8_t> last;
    dds::SampleMeta::Key writer{};
  };
  std::string topic_;
  dds::Reader<T> reader_;
  T sample_;
  OnSample on_sample_;
  OnLost on_lost_;
  std::map<dds::SampleMeta::Key, Instance> instances_;
};

}  // namespace

int RunRecorder(const RecordConfig& config) {
  const auto& where = config.where;
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  SessionStart start;
  start.name = where.session;
  start.domain_id = where.domain_id;
  start.host = host;
  start.pid = getpid();
  start.unix_ns = common::UnixNowNs();
  auto writer = std::make_unique<RecordingWriter>(config.out, start, config.flush_period);
  SessionLog& log = writer->log();

  // The session log, rebuilt as the world server writes it: members, worlds, control events.
  MemberRegistry members;
  const auto log_member = [&](const std::optional<MemberEvent>& e, std::int64_t unix_ns) {
    if (e) log.OnMember(e->change, e->member, static_cast<std::uint64_t>(unix_ns));
  };
  std::string scene_name;
  std::uint32_t scene_revision = 0;

  // The participant and its taps, made again when a member the world server has stays unheard
  // (a secured handshake with that member's participant that never finished): a new
  // participant starts a new handshake with everyone. The recording and its log go on.
  std::unique_ptr<dds::Participant> participant;
  std::vector<std::unique_ptr<TopicTap>> taps;
  dds::Reader<msg::SessionRoster> roster_reader;
  namespace t = dds::topics;
  const auto join = [&] {
    participant = std::make_unique<dds::Participant>(where, "session_record");
    dds::Participant& p = *participant;
    taps.push_back(std::make_unique<Tap<msg::MemberInfo>>(
        p, t::kMemberInfo,
        [&](const msg::MemberInfo& info, const dds::SampleMeta& meta, std::int64_t unix_ns) {
          if (meta.valid_data && meta.instance_state == dds::InstanceState::kAlive) {
            log_member(members.OnInfo(meta.instance, meta.writer, ToMember(info)), unix_ns);
          } else if (meta.instance_state != dds::InstanceState::kAlive) {
            log_member(members.OnGone(meta.instance, meta.instance_state == dds::InstanceState::kDisposed), unix_ns);
          }
        },
        [&](const dds::SampleMeta::Key& writer_key, std::int64_t unix_ns) {
          for (const auto& e : members.OnWriterLost(writer_key)) log_member(e, unix_ns);
        }));
    taps.push_back(std::make_unique<Tap<msg::SceneState>>(
        p, t::kSceneState, [&](const msg::SceneState& s, const dds::SampleMeta& meta, std::int64_t unix_ns) {
          if (!meta.valid_data || (s.scene() == scene_name && s.revision() == scene_revision)) return;
          scene_name = s.scene().to_string();
          scene_revision = s.revision();
          // The scene state carries no title: the report names worlds by their scene.
          log.OnSceneChange(scene_name, "", static_cast<std::uint64_t>(unix_ns));
        }));
    taps.push_back(std::make_unique<Tap<msg::MessageBoard>>(p, t::kMessageBoard));
    taps.push_back(std::make_unique<Tap<msg::DeviceState>>(p, t::kDeviceState));
    taps.push_back(std::make_unique<Tap<msg::ContactSet>>(p, t::kContactSet));
    taps.push_back(std::make_unique<Tap<msg::ObjectState>>(p, t::kObjectState));
    taps.push_back(std::make_unique<Tap<msg::Deformation>>(p, t::kDeformation));
    taps.push_back(std::make_unique<Tap<msg::ControlState>>(p, t::kControlState));
    taps.push_back(std::make_unique<Tap<msg::ControlEvent>>(
        p, t::kControlEvent, [&](const msg::ControlEvent& e, const dds::SampleMeta& meta, std::int64_t unix_ns) {
          if (!meta.valid_data) return;
          if (const auto input = ToControlInput(e)) {
            log.OnControlEvent(ToControlRecord(e, *input, static_cast<std::uint64_t>(unix_ns)));
          }
        }));
    taps.push_back(std::make_unique<Tap<msg::LoopStatistics>>(p, t::kLoopStatistics));
    roster_reader = dds::MakeReader<msg::SessionRoster>(p, t::kSessionRoster);
  };
  const auto leave = [&] {  // readers before their participant
    roster_reader = {};
    taps.clear();
    participant.reset();
  };
  join();
  dds::RosterRejoin roster(config.rejoin_after, where.session);
  auto roster_checked = SteadyClock::now();
  std::printf("[session_record] recording session '%s' on domain %d into %s\n", where.session.c_str(),
              where.domain_id, config.out.c_str());
  std::fflush(stdout);
  const std::int64_t t0 = SteadyNs();
  const auto start_time = SteadyClock::now();
  std::int64_t taken = 0;
  // Readers keep the last sample of each instance (stream topics keep-last 1): take them every
  // millisecond, well inside the 10 ms between a haptic node's device states.
  while (!common::ShutdownRequested()) {
    const auto now = SteadyClock::now();
    if (where.duration.count() > 0 && now - start_time >= where.duration) break;
    for (auto& tap : taps) taken += tap->Drain(*writer, t0);
    if (now - roster_checked >= std::chrono::milliseconds(100)) {
      roster_checked = now;
      roster.Take(roster_reader);
      std::vector<std::string> heard;
      for (const Member& m : members.present()) heard.push_back(m.member_id);
      if (const std::string why = roster.Due(heard, now); !why.empty()) {
        std::printf("[session_record] %s\n", why.c_str());
        std::fflush(stdout);
        for (auto& tap : taps) taken += tap->Drain(*writer, t0);
        SteadyClock::time_point opened;
        const std::string joined = node::RunRejoin(roster.rejoins(), SteadyClock::now(), leave, join, opened);
        std::printf("[session_record] %s\n", joined.c_str());
        std::fflush(stdout);
        roster.Restart(opened);
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  for (auto& tap : taps) taken += tap->Drain(*writer, t0);
  leave();
  writer->Finish(static_cast<std::int64_t>(common::UnixNowNs()));
  const double seconds = std::chrono::duration<double>(SteadyClock::now() - start_time).count();
  std::printf("[session_record] recorded %lld samples in %.1f s into %s\n", static_cast<long long>(writer->written()),
              seconds, config.out.c_str());
  std::fflush(stdout);
  return 0;
}

// ---------------------------------------------------------------------------------------------
// Player

namespace {

class TopicOut {
 public:
  virtual ~TopicOut() = default;
  virtual void Publish(const std::filesystem::path& file, const RecordedSample& s) = 0;
  virtual int matched_readers() const = 0;
  virtual bool WaitForAcknowledgments(std::chrono::nanoseconds timeout) = 0;
};

template <class T>
class Out : public TopicOut {
 public:
  Out(dds::Participant& p, const dds::topics::TopicSpec& spec)
      : writer_(dds::MakeWriter<T>(p, spec)), session_(p.session()) {}
  int matched_readers() const override { return writer_.matched_readers(); }
  bool WaitForAcknowledgments(std::chrono::nanoseconds timeout) override {
    return writer_.WaitForAcknowledgments(timeout);
  }
  void Publish(const std::filesystem::path& file, const RecordedSample& s) override {
    if (s.cdr.empty()) return;
    try {
      dds::Deserialize(s.cdr, sample_);
    } catch (const dds::SerializationError& e) {
      throw RecordingError(Where(file) + ": sample #" + std::to_string(s.id) + " (topic " + s.topic + ", offset " +
                           std::to_string(e.offset()) + " bytes into its payload): " + e.what());
    }
    // Every sample names its session, and receivers drop another session's: played into
    // another session, the samples are that session's.
    sample_.session(session_);
    switch (s.state) {
      case RecordedState::kAlive:
        writer_.Write(sample_);
        break;
      case RecordedState::kDisposed:
        writer_.Dispose(sample_);
        break;
      default:  // a lost writer cannot be replayed as such: the instance simply stays
        break;
    }
  }

 private:
  dds::Writer<T> writer_;
  std::string session_;
  T sample_;
};

}  // namespace

int RunPlayer(const PlayConfig& config) {
  RecordingReader reader(config.file);
  const RecordingInfo& info = reader.info();
  const auto& where = config.where;
  dds::Participant participant(where, "session_play");
  // The player is the session's source of truth, as a world server would be, but named and
  // marked as a replay: device "replay" tells it from a live server. Recorded members are not
  // announced again: they are not here, and a world server must not wait for them.
  dds::MemberAnnouncement member(participant, "player", msg::NODE_WORLD_SERVER, "replay");
  namespace t = dds::topics;
  std::map<std::string, std::unique_ptr<TopicOut>> outs;
  outs[t::kSceneState.name] = std::make_unique<Out<msg::SceneState>>(participant, t::kSceneState);
  outs[t::kMessageBoard.name] = std::make_unique<Out<msg::MessageBoard>>(participant, t::kMessageBoard);
  outs[t::kDeviceState.name] = std::make_unique<Out<msg::DeviceState>>(participant, t::kDeviceState);
  outs[t::kContactSet.name] = std::make_unique<Out<msg::ContactSet>>(participant, t::kContactSet);
  outs[t::kObjectState.name] = std::make_unique<Out<msg::ObjectState>>(participant, t::kObjectState);
  outs[t::kDeformation.name] = std::make_unique<Out<msg::Deformation>>(participant, t::kDeformation);
  outs[t::kControlEvent.name] = std::make_unique<Out<msg::ControlEvent>>(participant, t::kControlEvent);
  outs[t::kLoopStatistics.name] = std::make_unique<Out<msg::LoopStatistics>>(participant, t::kLoopStatistics);
  outs[t::kControlState.name] = std::make_unique<Out<msg::ControlState>>(participant, t::kControlState);

  std::printf("[session_play] playing %s (session '%s', %lld samples) into session '%s' on domain %d at speed %g\n",
              config.file.c_str(), info.session.c_str(), static_cast<long long>(info.samples), where.session.c_str(),
              where.domain_id, config.speed);
  std::fflush(stdout);
  if (config.wait_for_readers > 0) {
    const auto until = SteadyClock::now() + std::chrono::duration_cast<SteadyClock::duration>(config.wait_timeout);
    // Spectators read the scene and the deformations: both writers must have matched them.
    const auto matched = [&] {
      return std::min(outs[t::kSceneState.name]->matched_readers(), outs[t::kDeformation.name]->matched_readers());
    };
    while (matched() < config.wait_for_readers) {
      if (common::ShutdownRequested()) return 0;
      if (SteadyClock::now() > until) {
        throw RecordingError("no " + std::to_string(config.wait_for_readers) + " scene-state and deformation readers matched within " +
                             std::to_string(config.wait_timeout.count()) + " s (--wait-for-readers)");
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  RecordedSample s;
  std::optional<std::int64_t> first_ns;
  SteadyClock::time_point start;
  std::int64_t played = 0;
  while (!common::ShutdownRequested() && reader.Next(s)) {
    if (s.topic == t::kMemberInfo.name) continue;
    if (!first_ns) {
      first_ns = s.steady_ns;
      start = SteadyClock::now();
    }
    const auto due = start + std::chrono::duration_cast<SteadyClock::duration>(
                                 std::chrono::duration<double>(static_cast<double>(s.steady_ns - *first_ns) * 1e-9 /
                                                               config.speed));
    std::this_thread::sleep_until(due);
    const auto it = outs.find(s.topic);
    if (it == outs.end()) {
      throw RecordingError(Where(config.file) + ": sample #" + std::to_string(s.id) + ": unknown topic '" + s.topic + "'");
    }
    it->second->Publish(config.file, s);
    ++played;
  }
  std::printf("[session_play] played %lld samples\n", static_cast<long long>(played));
  std::fflush(stdout);
  // A reader the writer matched may not have matched the writer yet: with DDS-Security each
  // side matches when the other's crypto tokens reach it, and a lost token message is resent
  // only later. Such a reader acknowledges nothing until then, and then gets the transient-local
  // scene, board and deformations. Leaving before that would leave it with nothing.
  const auto deliver_start = SteadyClock::now();
  const auto deliver_until = deliver_start + std::chrono::duration_cast<SteadyClock::duration>(config.deliver_timeout);
  std::vector<std::string> unacknowledged;
  for (const auto* topic : {t::kSceneState.name, t::kMessageBoard.name, t::kDeformation.name, t::kControlEvent.name}) {
    const auto left = std::max(SteadyClock::duration::zero(), deliver_until - SteadyClock::now());
    if (!outs[topic]->WaitForAcknowledgments(left)) unacknowledged.emplace_back(topic);
  }
  const double waited = std::chrono::duration<double>(SteadyClock::now() - deliver_start).count();
  if (unacknowledged.empty()) {
    std::printf("[session_play] every matched reader acknowledged the reliable topics %.3f s after the last sample\n",
                waited);
    std::fflush(stdout);
  } else {
    std::string topics;
    for (const auto& u : unacknowledged) topics += (topics.empty() ? "" : ", ") + u;
    std::fprintf(stderr, "[session_play] warning: not every matched reader acknowledged %s within %g s (--deliver-timeout)\n",
                 topics.c_str(), config.deliver_timeout.count());
  }
  // The scene and the board stay transient-local for late joiners while the player holds.
  const auto until = SteadyClock::now() + std::chrono::duration_cast<SteadyClock::duration>(config.hold);
  while (!common::ShutdownRequested() && SteadyClock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return 0;
}

}  // namespace handshare::server
