// A member's leave over a lossy link, with the shipped member_info profiles
// (deploy/qos/handshare_qos.xml): MemberAnnouncement writes the join, then "leaving", then the
// dispose on one instance. When the datagram carrying "leaving" is lost, the writer must still
// have it to repair: a writer that kept only the last sample replaced it with the dispose, and
// every reader that missed it counted a lost reliable sample (session.scale failed so in CI:
// a screen and a hand each lost one while the other nodes left).
//
// Two participants in this process, over UDP only; the writer's transport is Fast DDS's test
// transport, which drops the first DATA of the writer's second sample.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/test_UDPv4TransportDescriptor.h>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "handshare/common/data_dir.hpp"
#include "handshare/dds/topics.hpp"
#include "handshare/idl/handsharePubSubTypes.h"
#include "rtps_test_support.hpp"

namespace handshare::dds {
namespace {

namespace fdds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;
using Clock = std::chrono::steady_clock;
using eprosima::fastrtps::types::ReturnCode_t;

constexpr int kMembers = 8;

std::mutex drops_mutex;
std::set<std::uint32_t> dropped_from;  // the writers (entity keys) whose leaving sample was dropped

// True for the first datagram of each user writer with a key (entity kind 0x02) holding a DATA
// submessage of sequence number 2: that member's "leaving" sample. Its repairs pass.
bool DropEachFirstLeavingSample(rtps::CDRMessage_t& msg) {
  return test_support::AnyData(msg, [](const test_support::DataSubmessage& data) {
    if (data.writer_id[3] != 0x02 || data.sequence != 2) return false;
    const auto writer = static_cast<std::uint32_t>(data.writer_id[0] << 16 | data.writer_id[1] << 8 | data.writer_id[2]);
    std::lock_guard<std::mutex> lock(drops_mutex);
    return dropped_from.insert(writer).second;
  });
}

bool WaitUntil(const std::function<bool()>& done, std::chrono::seconds timeout) {
  const auto end = Clock::now() + timeout;
  while (!done()) {
    if (Clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

// Eight members leave, as at the end of a session; each one's "leaving" datagram is lost once.
// Every "leaving" must still arrive, and no reader may count a loss. With the writer's history
// depth 1 no "leaving" arrived, in every run, and the reader counted losses in most runs.
TEST(MemberLeave, LostLeavingSamplesAreRepairedNotCountedLost) {
  test_support::TalkOverTransports();
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  const std::string profiles = (common::QosDir() / "handshare_qos.xml").string();
  ASSERT_TRUE(factory->load_XML_profiles_file(profiles) == ReturnCode_t::RETCODE_OK) << profiles;

  constexpr int kDomain = 164;
  fdds::DomainParticipant* reader_side =
      factory->create_participant(kDomain, test_support::OnlyOver(std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>()));
  auto lossy = std::make_shared<eprosima::fastdds::rtps::test_UDPv4TransportDescriptor>();
  lossy->messages_filter_ = DropEachFirstLeavingSample;
  fdds::DomainParticipant* writer_side = factory->create_participant(kDomain, test_support::OnlyOver(lossy));
  ASSERT_NE(reader_side, nullptr);
  ASSERT_NE(writer_side, nullptr);
  fdds::TypeSupport type(new msg::MemberInfoPubSubType());
  type.register_type(reader_side);
  type.register_type(writer_side);
  const std::string name = topics::kMemberInfo.name;
  fdds::Topic* rt = reader_side->create_topic(name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  fdds::Topic* wt = writer_side->create_topic(name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  // The shipped reader profile, keeping every sample: its depth of one lets the dispose replace
  // a repaired "leaving" before it is taken, and this test looks for every one.
  fdds::Subscriber* subscriber = reader_side->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  fdds::DataReaderQos reader_qos;
  ASSERT_TRUE(subscriber->get_datareader_qos_from_profile(topics::kMemberInfo.reader_profile, reader_qos) ==
              ReturnCode_t::RETCODE_OK);
  reader_qos.history().kind = fdds::KEEP_ALL_HISTORY_QOS;
  reader_qos.resource_limits().max_samples_per_instance = 4;
  reader_qos.resource_limits().max_samples = 4 * reader_qos.resource_limits().max_instances;
  fdds::DataReader* reader = subscriber->create_datareader(rt, reader_qos);
  ASSERT_NE(reader, nullptr);
  fdds::Publisher* publisher = writer_side->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  std::vector<fdds::DataWriter*> writers;
  for (int k = 0; k < kMembers; ++k) {
    writers.push_back(publisher->create_datawriter_with_profile(wt, topics::kMemberInfo.writer_profile));
    ASSERT_NE(writers.back(), nullptr);
  }
  ASSERT_TRUE(WaitUntil(
      [&] {
        fdds::SubscriptionMatchedStatus r;
        reader->get_subscription_matched_status(r);
        return r.current_count == kMembers;
      },
      std::chrono::seconds(10)))
      << "the member reader did not match the " << kMembers << " writers in 10 s";

  int joins = 0, leaves = 0, disposes = 0;
  const auto take = [&] {
    msg::MemberInfo sample;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
      if (info.valid_data) ++(sample.leaving() ? leaves : joins);
      // The dispose itself (a sample taken with it reads disposed too).
      if (!info.valid_data && info.instance_state == fdds::NOT_ALIVE_DISPOSED_INSTANCE_STATE) ++disposes;
    }
  };
  std::vector<msg::MemberInfo> members(kMembers);
  for (int k = 0; k < kMembers; ++k) {
    members[k].member_id("leave-test/user" + std::to_string(k + 1));
    members[k].user("user" + std::to_string(k + 1));
    ASSERT_TRUE(writers[k]->write(&members[k]));
  }
  ASSERT_TRUE(WaitUntil([&] { take(); return joins == kMembers; }, std::chrono::seconds(5)))
      << joins << " of " << kMembers << " joins came";
  // The leaves as MemberAnnouncement's destructor sends them.
  for (int k = 0; k < kMembers; ++k) {
    members[k].leaving(true);
    ASSERT_TRUE(writers[k]->write(&members[k]));
    ASSERT_TRUE(writers[k]->dispose(&members[k], fdds::HANDLE_NIL) == ReturnCode_t::RETCODE_OK);
  }
  const bool disposed = WaitUntil([&] { take(); return disposes == kMembers; }, std::chrono::seconds(5));
  // The reader counts a loss when a heartbeat says the writer no longer has a sample; once each
  // writer has every acknowledgment, the count is final.
  bool acknowledged = true;
  for (fdds::DataWriter* w : writers) {
    acknowledged &= w->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(5, 0)) == ReturnCode_t::RETCODE_OK;
  }
  fdds::SampleLostStatus lost;
  reader->get_sample_lost_status(lost);
  writer_side->delete_contained_entities();
  reader_side->delete_contained_entities();
  factory->delete_participant(writer_side);
  factory->delete_participant(reader_side);

  {
    std::lock_guard<std::mutex> lock(drops_mutex);
    ASSERT_EQ(dropped_from.size(), static_cast<std::size_t>(kMembers))
        << "not every leaving sample's datagram was dropped: the test tested less than it says";
  }
  EXPECT_EQ(leaves, kMembers) << "leaving samples lost for good: their writers no longer had them";
  EXPECT_TRUE(disposed) << disposes << " of " << kMembers << " disposes came";
  EXPECT_TRUE(acknowledged) << "the reader did not acknowledge everything in 5 s";
  EXPECT_EQ(lost.total_count, 0) << "the reader counted leaving samples lost: their writers no longer had them";
}

}  // namespace
}  // namespace handshare::dds
