#pragma once
/// Recording and replay of a whole session (session_record, session_play).
///
/// A recording is one SQLite file that is also a session log (application_id "HSLG", schema of
/// session_schema.hpp: members, worlds and control events rebuilt live from the recorded topics,
/// so session_report reads a recording as it reads a world server's log) with three more tables:
///   recording(format_version, session, domain_id, started/ended times, samples, dropped),
///   instances(id, topic, key): a DDS instance (its 16-byte key hash) of a topic,
///   samples(id, steady_ns, unix_ns, topic, instance, state, cdr): every sample received, in
///     order of reception; steady_ns counts from the recording's start; cdr is the sample as
///     the wire carries it (dds::Serialize); state says alive, disposed, no writers or
///     writer lost (a dispose or loss carries the instance's last sample, so a player can
///     dispose it by key).
/// Why SQLite: the project already writes and reads session logs with it (one dependency, one
/// helper), a recording killed mid-way keeps every committed batch (WAL), a corrupt or truncated
/// file is detected by SQLite's page checks instead of being read as garbage, and the samples
/// are indexed by time for seeking and by topic for reports; the overhead over a flat file is
/// a few bytes of row header per sample (docs/network.md, "Recording and replay").
///
/// Writes never happen on the DDS thread: the recorder takes samples, serializes them and
/// queues them; a writer thread inserts them in one transaction per flush period.
#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "handshare/common/session_options.hpp"

namespace handshare::server {

/// A recording that cannot be created, read or played: what() names the file and, where known,
/// the sample (row id), its topic and the byte offset into its payload, or the byte offset of
/// the file where it is cut short.
class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class RecordedState : int { kAlive = 0, kDisposed = 1, kNoWriters = 2, kWriterLost = 3 };

struct RecordedSample {
  std::int64_t id = 0;                  ///< row id: order of reception, from 1
  std::int64_t steady_ns = 0;           ///< receive time since the recording started (steady clock)
  std::int64_t unix_ns = 0;             ///< receive time, wall clock
  std::string topic;                    ///< e.g. "handshare/device_state"
  std::array<std::uint8_t, 16> instance{};  ///< key hash (zeros for the keyless control events)
  RecordedState state = RecordedState::kAlive;
  std::vector<std::uint8_t> cdr;        ///< the sample (empty: a dispose of an instance never seen)
};

struct RecordingInfo {
  int format_version = 0;
  std::string session;
  int domain_id = 0;
  std::int64_t started_unix_ns = 0;
  std::int64_t ended_unix_ns = 0;       ///< 0: the recorder did not end cleanly
  std::int64_t samples = 0;             ///< rows in samples
  std::int64_t dropped = 0;             ///< samples the disk could not keep up with
};

struct SessionStart;
class SessionLog;
namespace detail {
class RecordingWriterImpl;
}

/// Creates a recording (the file must not exist) and inserts samples on its own thread, one
/// transaction per flush period. The recorder's; public for tests that make recordings.
class RecordingWriter {
 public:
  RecordingWriter(const std::filesystem::path& file, const SessionStart& start,
                  std::chrono::milliseconds flush_period = std::chrono::milliseconds(250));
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;
  /// Queues a sample (id is assigned by the file); thread-safe, never waits on the disk.
  void Push(RecordedSample sample);
  /// Commits what is queued and writes the end; throws RecordingError after a write error.
  void Finish(std::int64_t ended_unix_ns);
  /// The session log the recording also is (members, worlds, control events).
  SessionLog& log();
  std::int64_t written() const;

 private:
  std::unique_ptr<detail::RecordingWriterImpl> impl_;
};

/// The topics a recording holds, in topics.hpp's names.
const std::vector<std::string>& RecordedTopics();

/// Reads a recording in order of reception. Checks the file before SQLite does (SQLite header,
/// size against the page count the header states) so a cut file names the byte it ends at.
class RecordingReader {
 public:
  static constexpr int kFormatVersion = 1;
  explicit RecordingReader(const std::filesystem::path& file);
  ~RecordingReader();
  RecordingReader(const RecordingReader&) = delete;
  RecordingReader& operator=(const RecordingReader&) = delete;

  const RecordingInfo& info() const { return info_; }
  /// The next sample; false at the end. Throws RecordingError naming the file and the sample.
  bool Next(RecordedSample& sample);
  const std::filesystem::path& file() const { return file_; }

 private:
  struct Impl;
  std::filesystem::path file_;
  RecordingInfo info_;
  std::unique_ptr<Impl> impl_;
  std::int64_t last_id_ = 0;
};

/// Deserializes every sample of a recording and checks its topic and state; throws
/// RecordingError naming the file, the sample, its topic and the payload offset of the first
/// bad one. Returns the number of samples.
std::int64_t VerifyRecording(const std::filesystem::path& file);

struct RecordConfig {
  common::SessionOptions where;         ///< duration 0: until SIGINT/SIGTERM
  std::filesystem::path out;            ///< must not exist
  std::chrono::milliseconds flush_period{250};
  /// A member the world server has (its roster) and this recorder has not heard this long:
  /// join again with a new participant; 0: never.
  std::chrono::duration<double> rejoin_after{15.0};
};
/// session_record: records every topic of the session until the duration passes or a signal.
int RunRecorder(const RecordConfig& config);

struct PlayConfig {
  common::SessionOptions where;
  std::filesystem::path file;
  double speed = 1.0;                   ///< 2: twice as fast
  int wait_for_readers = 0;             ///< start the clock once this many spectators match (scene state and deformation)
  std::chrono::duration<double> wait_timeout{30.0};
  /// After the last sample, wait at most this long for every matched reader to acknowledge the
  /// reliable topics (scene, board, deformations, control events); a warning if one did not.
  std::chrono::duration<double> deliver_timeout{10.0};
  std::chrono::duration<double> hold{1.0};  ///< then stay this long (late joiners)
};
/// session_play: republishes a recording with its original timing scaled by 1 / speed.
int RunPlayer(const PlayConfig& config);

}  // namespace handshare::server
