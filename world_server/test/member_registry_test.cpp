#include "handshare/world_server/member_registry.hpp"

#include <gtest/gtest.h>

namespace handshare::server {
namespace {

InstanceKey Key(std::uint8_t k) {
  InstanceKey key{};
  key[0] = k;
  return key;
}

TEST(MemberRegistry, JoinLeaveLostAreReportedOnce) {
  MemberRegistry r;
  auto joined = r.OnInfo(Key(1), Key(101), Member{"s/alice", "alice", "haptic", "sim", 10});
  ASSERT_TRUE(joined);
  EXPECT_EQ(joined->change, MemberChange::kJoined);
  EXPECT_FALSE(r.OnInfo(Key(1), Key(101), Member{"s/alice", "alice", "haptic", "hiro", 10}));  // update
  ASSERT_TRUE(r.OnInfo(Key(2), Key(102), Member{"s/bob", "bob", "haptic", "sim", 11}));
  EXPECT_EQ(r.present().size(), 2u);

  auto left = r.OnGone(Key(1), /*disposed=*/true);
  ASSERT_TRUE(left);
  EXPECT_EQ(left->change, MemberChange::kLeft);
  EXPECT_EQ(left->member.device, "hiro");  // the newest info is what is reported
  EXPECT_FALSE(r.OnGone(Key(1), false));   // no second report

  auto lost = r.OnGone(Key(2), /*disposed=*/false);
  ASSERT_TRUE(lost);
  EXPECT_EQ(lost->change, MemberChange::kLost);
  EXPECT_TRUE(r.present().empty());
  EXPECT_EQ(r.joined_total(), 2u);
}

TEST(MemberRegistry, LostWriterLosesItsMembersOnly) {
  MemberRegistry r;
  r.OnInfo(Key(1), Key(101), Member{"s/alice", "alice", "haptic", "sim", 10});
  r.OnInfo(Key(2), Key(102), Member{"s/bob", "bob", "haptic", "sim", 11});
  const auto lost = r.OnWriterLost(Key(102));
  ASSERT_EQ(lost.size(), 1u);
  EXPECT_EQ(lost[0].change, MemberChange::kLost);
  EXPECT_EQ(lost[0].member.user, "bob");
  EXPECT_TRUE(r.OnWriterLost(Key(102)).empty());  // reported once
  EXPECT_FALSE(r.OnGone(Key(2), false));          // and not again as no-writers
  ASSERT_EQ(r.present().size(), 1u);
  // A clean leave first, then the writer's unmatch: only the leave is reported.
  ASSERT_TRUE(r.OnGone(Key(1), true));
  EXPECT_TRUE(r.OnWriterLost(Key(101)).empty());
}

TEST(MemberRegistry, UnknownInstanceGoneIsIgnored) {
  MemberRegistry r;
  EXPECT_FALSE(r.OnGone(Key(9), true));
}

}  // namespace
}  // namespace handshare::server
