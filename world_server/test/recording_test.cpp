// A recording reads back sample for sample; a cut, corrupt or foreign file is refused with a
// message that names the file and where (byte, sample, topic, payload offset); the recording is
// a session log too, so session_report's reader takes it.
#include "handshare/world_server/recording.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <fstream>

#include "handshare/dds/serialization.hpp"
#include "handshare/world_server/session_log.hpp"
#include "handshare/world_server/session_report.hpp"
#include "test_support.hpp"

namespace handshare::server {
namespace {

using testing::kSecond;
using testing::kT0;
using testing::TempDir;

RecordedSample Sample(const std::string& topic, std::int64_t t_ns, std::vector<std::uint8_t> cdr,
                      RecordedState state = RecordedState::kAlive, std::uint8_t key = 1) {
  RecordedSample s;
  s.steady_ns = t_ns;
  s.unix_ns = static_cast<std::int64_t>(kT0) + t_ns;
  s.topic = topic;
  s.instance[0] = key;
  s.state = state;
  s.cdr = std::move(cdr);
  return s;
}

msg::DeviceState Device(int i) {
  msg::DeviceState d;
  d.user("alice");
  d.session("museum");
  d.stamp_ns(static_cast<std::uint64_t>(i) * 10000000ULL);
  d.seq(static_cast<std::uint32_t>(i));
  d.p_WE_m()[1] = {0.01 * i, 0.0, 0.1};
  return d;
}

// A recording of a scene state, a member who joins and leaves, and `devices` device states.
std::filesystem::path MakeRecording(const TempDir& dir, int devices) {
  const auto file = dir / "rec.db";
  SessionStart start;
  start.name = "museum";
  start.domain_id = 7;
  start.host = "test";
  start.unix_ns = kT0;
  RecordingWriter writer(file, start, std::chrono::milliseconds(20));
  msg::SceneState scene;
  scene.session("museum");
  scene.scene("dinosaur");
  scene.revision(1);
  writer.Push(Sample(dds::topics::kSceneState.name, 0, dds::Serialize(scene)));
  msg::MemberInfo member;
  member.member_id("museum/alice");
  member.user("alice");
  const auto member_cdr = dds::Serialize(member);
  writer.Push(Sample(dds::topics::kMemberInfo.name, 1000, member_cdr, RecordedState::kAlive, 2));
  for (int i = 0; i < devices; ++i) {
    writer.Push(Sample(dds::topics::kDeviceState.name, 2000 + i * 10000000LL, dds::Serialize(Device(i)),
                       RecordedState::kAlive, 3));
  }
  writer.Push(Sample(dds::topics::kMemberInfo.name, 5 * static_cast<std::int64_t>(kSecond), member_cdr,
                     RecordedState::kDisposed, 2));
  writer.log().OnSceneChange("dinosaur", "", kT0);
  writer.Finish(static_cast<std::int64_t>(kT0 + 6 * kSecond));
  return file;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const RecordingError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Recording, ReadsBackEverySampleInOrder) {
  TempDir dir;
  const auto file = MakeRecording(dir, 50);
  RecordingReader reader(file);
  EXPECT_EQ(reader.info().session, "museum");
  EXPECT_EQ(reader.info().domain_id, 7);
  EXPECT_EQ(reader.info().samples, 53);
  EXPECT_EQ(reader.info().ended_unix_ns, static_cast<std::int64_t>(kT0 + 6 * kSecond));
  RecordedSample s;
  ASSERT_TRUE(reader.Next(s));
  EXPECT_EQ(s.topic, dds::topics::kSceneState.name);
  msg::SceneState scene;
  dds::Deserialize(s.cdr, scene);
  EXPECT_EQ(scene.scene(), "dinosaur");
  ASSERT_TRUE(reader.Next(s));
  EXPECT_EQ(s.topic, dds::topics::kMemberInfo.name);
  EXPECT_EQ(s.instance[0], 2);
  for (int i = 0; i < 50; ++i) {
    ASSERT_TRUE(reader.Next(s));
    EXPECT_EQ(s.steady_ns, 2000 + i * 10000000LL);
    msg::DeviceState d;
    dds::Deserialize(s.cdr, d);
    EXPECT_EQ(d, Device(i));
  }
  ASSERT_TRUE(reader.Next(s));
  EXPECT_EQ(s.state, RecordedState::kDisposed);
  msg::MemberInfo member;
  dds::Deserialize(s.cdr, member);
  EXPECT_EQ(member.member_id(), "museum/alice");  // a dispose carries the key
  EXPECT_FALSE(reader.Next(s));
  EXPECT_EQ(VerifyRecording(file), 53);
}

TEST(Recording, IsASessionLogThatTheReportReads) {
  TempDir dir;
  const auto file = MakeRecording(dir, 2);
  const auto report = ReadReport(file, std::nullopt);
  std::ostringstream out;
  PrintReport(out, report);
  EXPECT_NE(out.str().find("dinosaur"), std::string::npos) << out.str();
}

TEST(Recording, ATruncatedFileNamesTheFileAndTheByteItEndsAt) {
  TempDir dir;
  const auto file = MakeRecording(dir, 2000);
  const auto size = std::filesystem::file_size(file);
  std::filesystem::resize_file(file, size / 2);
  const std::string error = ErrorOf([&] { VerifyRecording(file); });
  EXPECT_NE(error.find(file.string()), std::string::npos) << error;
  EXPECT_NE(error.find("truncated at byte " + std::to_string(size / 2)), std::string::npos) << error;
  std::filesystem::resize_file(file, 50);
  EXPECT_NE(ErrorOf([&] { VerifyRecording(file); }).find("shorter than SQLite's 100-byte header"), std::string::npos);
}

TEST(Recording, ACorruptPageNamesTheFileAndTheLastGoodSample) {
  TempDir dir;
  const auto file = MakeRecording(dir, 2000);
  const auto size = std::filesystem::file_size(file);
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(size / 2));
    const std::string garbage(8192, '\xA5');
    f.write(garbage.data(), static_cast<std::streamsize>(garbage.size()));
  }
  const std::string error = ErrorOf([&] { VerifyRecording(file); });
  EXPECT_NE(error.find(file.string()), std::string::npos) << error;
  EXPECT_TRUE(error.find("malformed") != std::string::npos || error.find("sample #") != std::string::npos) << error;
}

TEST(Recording, ASampleThatDoesNotDeserializeIsNamedWithItsTopicAndOffset) {
  TempDir dir;
  const auto file = MakeRecording(dir, 10);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "UPDATE samples SET cdr = substr(cdr, 1, 40) WHERE id = 5", nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  const std::string error = ErrorOf([&] { VerifyRecording(file); });
  EXPECT_NE(error.find(file.string() + ": sample #5 (topic handshare/device_state, offset "), std::string::npos)
      << error;
  EXPECT_NE(error.find("bytes into its payload"), std::string::npos) << error;
}

// A recording made before LoopStatistics had deadline_misses and sent_bytes_per_s (its samples
// 16 bytes shorter) still reads; a sample cut anywhere else is still refused.
TEST(Recording, LoopStatisticsRecordedBeforeTheirTrafficFieldsStillRead) {
  TempDir dir;
  msg::LoopStatistics stats;
  stats.node("haptic_node/alice");
  stats.session("museum");
  stats.samples_dropped(3);
  std::vector<std::uint8_t> cdr = dds::Serialize(stats);
  ASSERT_GT(cdr.size(), 20u);
  cdr.resize(cdr.size() - 16);  // the older type's payload
  msg::LoopStatistics decoded;
  EXPECT_THROW(dds::Deserialize(cdr, decoded), dds::SerializationError);  // this build's type alone refuses it
  std::vector<std::uint8_t> cut = cdr;
  cut.resize(cut.size() - 8);
  {
    RecordingWriter writer(dir / "old.db", SessionStart{"museum", 7, "test", 1, kT0}, std::chrono::milliseconds(20));
    writer.Push(Sample(dds::topics::kLoopStatistics.name, 1000, cdr));
    writer.Finish(static_cast<std::int64_t>(kT0 + kSecond));
  }
  EXPECT_EQ(VerifyRecording(dir / "old.db"), 1);
  {
    RecordingWriter writer(dir / "cut.db", SessionStart{"museum", 7, "test", 1, kT0}, std::chrono::milliseconds(20));
    writer.Push(Sample(dds::topics::kLoopStatistics.name, 1000, cut));
    writer.Finish(static_cast<std::int64_t>(kT0 + kSecond));
  }
  EXPECT_NE(ErrorOf([&] { VerifyRecording(dir / "cut.db"); }).find("topic handshare/loop_statistics"), std::string::npos);
}

TEST(Recording, ASessionLogIsNotARecordingAndAnExistingFileIsNotOverwritten) {
  TempDir dir;
  const auto log_file = dir / "log.db";
  {
    SessionStart start;
    start.name = "museum";
    SessionLog log(log_file, start);
  }
  EXPECT_NE(ErrorOf([&] { RecordingReader r(log_file); }).find("not a recording"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { RecordingWriter w(log_file, SessionStart{}); }).find("already exists"), std::string::npos);
  EXPECT_NE(ErrorOf([&] { RecordingReader r(dir / "none.db"); }).find("no such recording"), std::string::npos);
}

}  // namespace
}  // namespace handshare::server
