// In-process checks of the DDS layer over real Fast DDS (loopback), one domain per test.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <thread>
#include <vector>

#include "handshare/dds/loop_traffic.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/dds/serialization.hpp"

namespace handshare::dds {
namespace {

using namespace std::chrono_literals;

template <class T>
bool TakeWithin(Reader<T>& reader, T& sample, SampleMeta& meta, std::chrono::milliseconds t) {
  const auto end = std::chrono::steady_clock::now() + t;
  while (std::chrono::steady_clock::now() < end) {
    if (reader.TakeNext(sample, meta)) return true;
    reader.WaitForData(50ms);
  }
  return false;
}

// Best-effort: writes `out` until discovery has matched and one sample arrives (at most `tries`
// writes, each followed by a wait of `wait` for the take).
template <typename T>
bool WriteUntilTaken(Writer<T>& writer, const T& out, Reader<T>& reader, T& in, SampleMeta& meta, int tries,
                     std::chrono::milliseconds wait) {
  for (int i = 0; i < tries; ++i) {
    writer.Write(out);
    if (TakeWithin(reader, in, meta, wait)) return true;
  }
  return false;
}

TEST(DdsParticipant, StreamRoundTripKeepsEveryField) {
  Participant a(201, "s1", "writer"), b(201, "s1", "reader");
  auto writer = MakeWriter<msg::DeviceState>(a, topics::kDeviceState);
  auto reader = MakeReader<msg::DeviceState>(b, topics::kDeviceState);
  msg::DeviceState out;
  out.user("alice");
  out.seq(42);
  out.p_WE_m()[3][2] = 0.125;
  out.fingertip_radius_m(0.008);
  msg::DeviceState in;
  SampleMeta meta;
  ASSERT_TRUE(WriteUntilTaken(writer, out, reader, in, meta, 100, 50ms));
  EXPECT_TRUE(meta.valid_data);
  EXPECT_EQ(std::string(in.user().c_str()), "alice");
  EXPECT_EQ(in.seq(), 42u);
  EXPECT_DOUBLE_EQ(in.p_WE_m()[3][2], 0.125);
  EXPECT_DOUBLE_EQ(in.fingertip_radius_m(), 0.008);
}

// The device-state profile has a 100 ms deadline: a user that stops sending is counted, one
// that keeps sending every 10 ms is not.
TEST(DdsParticipant, AStalledDeviceStateStreamMissesItsDeadline) {
  Participant a(206, "s1", "writer"), b(206, "s1", "reader");
  auto writer = MakeWriter<msg::DeviceState>(a, topics::kDeviceState);
  auto reader = MakeReader<msg::DeviceState>(b, topics::kDeviceState);
  msg::DeviceState out;
  out.user("alice");
  msg::DeviceState in;
  SampleMeta meta;
  ASSERT_TRUE(WriteUntilTaken(writer, out, reader, in, meta, 200, 10ms));
  // Streaming at 100 Hz for 0.5 s: no period without a sample (at most one, where a loaded
  // machine held the writing thread back for 100 ms).
  const std::uint64_t before = reader.deadlines_missed();
  for (int i = 0; i < 50; ++i) {
    writer.Write(out);
    std::this_thread::sleep_for(10ms);
    while (reader.TakeNext(in, meta)) {
    }
  }
  EXPECT_LE(reader.deadlines_missed(), before + 1);
  const std::uint64_t streaming = reader.deadlines_missed();
  // Then silence for 0.45 s: at least 3 whole periods of 100 ms missed, by the reader and, as
  // it is matched, by the writer; each participant's total (its loop statistics) counts them.
  const std::uint64_t offered = a.DeadlinesMissed(), requested = b.DeadlinesMissed();
  std::this_thread::sleep_for(450ms);
  EXPECT_GE(reader.deadlines_missed(), streaming + 3);
  EXPECT_GE(b.DeadlinesMissed(), requested + 3);
  EXPECT_GE(a.DeadlinesMissed(), offered + 3);
  EXPECT_EQ(b.DeadlinesMissed(), reader.deadlines_missed());
  EXPECT_GT(a.WrittenBytes(), 51u * 4u);  // 51 samples at least, each more than its CDR header
}

// A writer nobody reads may fall silent (the haptic node stops its device states): no miss.
TEST(DdsParticipant, AnUnreadWriterMissesNoDeadline) {
  Participant a(211, "s1", "writer");
  auto writer = MakeWriter<msg::DeviceState>(a, topics::kDeviceState);
  msg::DeviceState out;
  out.user("alice");
  writer.Write(out);
  std::this_thread::sleep_for(350ms);
  EXPECT_EQ(a.DeadlinesMissed(), 0u);
}

// A node's loop statistics say the bytes its writers wrote per second of the period since the
// previous statistics, whichever topics they went to.
TEST(DdsParticipant, LoopTrafficIsTheBytesWrittenPerSecondOfThePeriod) {
  Participant a(212, "s1", "writer");
  const auto t0 = LoopTraffic::Clock::now();
  LoopTraffic traffic(a, t0);
  auto states = MakeWriter<msg::DeviceState>(a, topics::kDeviceState);
  auto boards = MakeWriter<msg::MessageBoard>(a, topics::kMessageBoard);
  msg::DeviceState state;
  state.user("alice");
  msg::MessageBoard board;
  board.text("hello");
  for (int i = 0; i < 10; ++i) states.Write(state);
  boards.Write(board);
  const std::uint64_t bytes = a.WrittenBytes();
  EXPECT_GT(bytes, 10u * 4u);
  msg::LoopStatistics out;
  traffic.Fill(out, t0 + 2s);
  EXPECT_DOUBLE_EQ(out.sent_bytes_per_s(), static_cast<double>(bytes) / 2.0);
  EXPECT_EQ(out.deadline_misses(), a.DeadlinesMissed());
  states.Write(state);
  traffic.Fill(out, t0 + 2500ms);  // one more sample in half a second
  EXPECT_DOUBLE_EQ(out.sent_bytes_per_s(), static_cast<double>(a.WrittenBytes() - bytes) / 0.5);
  traffic.Fill(out, t0 + 2500ms);  // no time: no rate
  EXPECT_EQ(out.sent_bytes_per_s(), 0.0);
}

// Deformations go through the asynchronous writer and its flow controller in 1400-byte
// fragments: the largest sample the IDL allows arrives whole.
TEST(DdsParticipant, TheLargestDeformationArrivesWholeThroughTheFlowController) {
  Participant a(207, "s1", "writer"), b(207, "s1", "reader");
  auto writer = MakeWriter<msg::Deformation>(a, topics::kDeformation);
  auto reader = MakeReader<msg::Deformation>(b, topics::kDeformation);
  msg::Deformation out;
  out.object_id("tail");
  out.revision(7);
  std::vector<std::uint32_t> ids(msg::kMaxSurfaceDelta);
  std::vector<float> u(3 * ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    ids[i] = static_cast<std::uint32_t>(i);
    u[3 * i + 2] = -1e-6f * static_cast<float>(i);
  }
  out.surface_node_count(static_cast<std::uint32_t>(ids.size()));
  out.node_ids(ids);
  out.u_W_m(u);
  for (int i = 0; i < 200 && writer.matched_readers() == 0; ++i) std::this_thread::sleep_for(10ms);
  ASSERT_GT(writer.matched_readers(), 0);
  writer.Write(out);
  msg::Deformation in;
  SampleMeta meta;
  ASSERT_TRUE(TakeWithin(reader, in, meta, 5000ms));
  EXPECT_EQ(in.revision(), 7u);
  ASSERT_EQ(in.node_ids().size(), ids.size());
  EXPECT_EQ(in.node_ids(), ids);
  EXPECT_EQ(in.u_W_m(), u);
}

TEST(DdsParticipant, LateJoinerReceivesTransientLocalState) {
  Participant server(202, "s1", "server");
  auto writer = MakeWriter<msg::MessageBoard>(server, topics::kMessageBoard);
  msg::MessageBoard board;
  board.session("s1");
  board.message_id(7);
  board.text("Welcome");
  writer.Write(board);
  std::this_thread::sleep_for(200ms);
  Participant late(202, "s1", "late");  // joins after the write
  auto reader = MakeReader<msg::MessageBoard>(late, topics::kMessageBoard);
  msg::MessageBoard in;
  SampleMeta meta;
  ASSERT_TRUE(TakeWithin(reader, in, meta, 5000ms));
  EXPECT_EQ(in.message_id(), 7u);
  EXPECT_EQ(std::string(in.text().c_str()), "Welcome");
}

// A reader that the writer matched but that cannot answer (here: its process stopped, shorter
// than the 1 s lease that would drop it) holds WaitForAcknowledgments until it answers; the
// session player relies on this to stay until a secured spectator's side has matched.
TEST(DdsParticipant, WaitForAcknowledgmentsWaitsUntilAMatchedReaderAnswers) {
  Participant server(208, "s1", "server");
  auto writer = MakeWriter<msg::MessageBoard>(server, topics::kMessageBoard);
  int out[2];
  ASSERT_EQ(pipe(out), 0);
  const pid_t helper = fork();
  ASSERT_GE(helper, 0);
  if (helper == 0) {
    dup2(out[1], STDOUT_FILENO);
    execl(HANDSHARE_RELIABLE_READER_HELPER, HANDSHARE_RELIABLE_READER_HELPER, "208", "s1", nullptr);
    _exit(127);
  }
  close(out[1]);
  char ready[6] = {};
  ASSERT_EQ(read(out[0], ready, 5), 5) << "the helper did not start";
  EXPECT_STREQ(ready, "ready");
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (writer.matched_readers() == 0 && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(10ms);
  ASSERT_EQ(writer.matched_readers(), 1);
  msg::MessageBoard board;
  board.session("s1");
  board.message_id(1);
  writer.Write(board);
  EXPECT_TRUE(writer.WaitForAcknowledgments(5s));

  ASSERT_EQ(kill(helper, SIGSTOP), 0);
  int status = 0;
  ASSERT_EQ(waitpid(helper, &status, WUNTRACED), helper);
  ASSERT_TRUE(WIFSTOPPED(status));
  board.message_id(2);
  writer.Write(board);
  const bool acknowledged_while_stopped = writer.WaitForAcknowledgments(300ms);
  ASSERT_EQ(kill(helper, SIGCONT), 0);
  EXPECT_FALSE(acknowledged_while_stopped);
  EXPECT_TRUE(writer.WaitForAcknowledgments(5s));
  kill(helper, SIGTERM);
  waitpid(helper, &status, 0);
  close(out[0]);
}

TEST(DdsParticipant, SessionsOnOneDomainAreIsolated) {
  Participant a(203, "room-a", "a"), b(203, "room-b", "b");
  auto writer = MakeWriter<msg::MessageBoard>(a, topics::kMessageBoard);
  auto reader = MakeReader<msg::MessageBoard>(b, topics::kMessageBoard);
  msg::MessageBoard board;
  board.session("room-a");
  writer.Write(board);
  msg::MessageBoard in;
  SampleMeta meta;
  EXPECT_FALSE(TakeWithin(reader, in, meta, 1000ms));
  EXPECT_EQ(writer.matched_readers(), 0);
}

TEST(DdsParticipant, DisposeIsSeenAsDisposedInstance) {
  Participant a(204, "s1", "member"), b(204, "s1", "server");
  auto reader = MakeReader<msg::MemberInfo>(b, topics::kMemberInfo);
  auto writer = MakeWriter<msg::MemberInfo>(a, topics::kMemberInfo);
  msg::MemberInfo info;
  info.member_id("s1/alice");
  info.user("alice");
  writer.Write(info);
  msg::MemberInfo in;
  SampleMeta joined;
  ASSERT_TRUE(TakeWithin(reader, in, joined, 5000ms));
  EXPECT_TRUE(joined.valid_data);
  EXPECT_EQ(joined.instance_state, InstanceState::kAlive);
  writer.Dispose(info);
  SampleMeta left;
  ASSERT_TRUE(TakeWithin(reader, in, left, 5000ms));
  EXPECT_EQ(left.instance_state, InstanceState::kDisposed);
  EXPECT_EQ(left.instance, joined.instance);  // the same member
}

// Every sample written and taken is counted per topic, on both sides (reliable keep-all
// events: every one written arrives).
TEST(DdsParticipant, TrafficCountsWrittenAndTakenSamplesPerTopic) {
  Participant a(205, "s1", "node"), b(205, "s1", "server");
  auto reader = MakeReader<msg::ControlEvent>(b, topics::kControlEvent);
  auto writer = MakeWriter<msg::ControlEvent>(a, topics::kControlEvent);
  const auto end = std::chrono::steady_clock::now() + 5s;
  while (writer.matched_readers() == 0 && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(10ms);
  ASSERT_EQ(writer.matched_readers(), 1);
  msg::ControlEvent event;
  event.session("s1");
  for (int i = 0; i < 7; ++i) writer.Write(event);
  msg::ControlEvent in;
  SampleMeta meta;
  int taken = 0;
  while (taken < 7 && TakeWithin(reader, in, meta, 5000ms)) ++taken;
  ASSERT_EQ(taken, 7);
  const auto find = [](const std::vector<TopicTraffic>& all, const std::string& topic) {
    for (const auto& t : all) {
      if (t.topic == topic) return t;
    }
    return TopicTraffic{};
  };
  const TopicTraffic out = find(a.Traffic(), std::string(topics::kControlEvent.name));
  const TopicTraffic got = find(b.Traffic(), std::string(topics::kControlEvent.name));
  EXPECT_EQ(out.written, 7u);
  EXPECT_EQ(out.written_bytes, 7u * Serialize(event).size());  // the CDR payload, header included
  EXPECT_EQ(out.taken, 0u);
  EXPECT_EQ(got.written, 0u);
  EXPECT_EQ(got.taken, 7u);
  EXPECT_EQ(got.lost, 0u);
  char summary[64];
  std::snprintf(summary, sizeof summary, "traffic: control_event out 7 (%.1f kB)", 7e-3 * static_cast<double>(Serialize(event).size()));
  EXPECT_EQ(a.TrafficSummary(), summary);
  EXPECT_EQ(b.TrafficSummary(), "traffic: control_event in 7");
  Participant idle(205, "s2", "idle");
  EXPECT_EQ(idle.TrafficSummary(), "traffic: none");
}

// Domain 209: ctest runs every case as a process of its own, two at a time, so a case that
// makes participants keeps to a domain no other case uses (this one shared 205 with the
// traffic case next to it, whose counts and discovery it then joined).
TEST(DdsParticipant, ClearErrorsForBadSetup) {
  EXPECT_THROW(Participant(300, "s", "p"), DdsError);           // domain out of range
  EXPECT_THROW(Participant(209, "", "p"), DdsError);            // no session
  try {
    Participant p(209, "s", "p", "/nonexistent/qos.xml");
    FAIL() << "expected DdsError";
  } catch (const DdsError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/qos.xml"), std::string::npos);
  }
  Participant p(209, "s", "p");
  try {
    p.CreateWriter<msg::MessageBoard>("handshare/x", "no_such_profile");
    FAIL() << "expected DdsError";
  } catch (const DdsError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_profile"), std::string::npos);
  }
}

}  // namespace
}  // namespace handshare::dds
