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

/// A writer of participant `p` (its first 12 bytes), entity `e`.
InstanceKey Writer(std::uint8_t p, std::uint8_t e) {
  InstanceKey key{};
  key[0] = p;
  key[11] = p;
  key[15] = e;
  return key;
}

TEST(MemberRegistry, OnlyTheParticipantThatAnnouncedAUserWritesInItsName) {
  MemberRegistry r;
  r.OnInfo(Key(1), Writer(7, 1), Member{"s/alice", "alice", "haptic", "sim", 10});
  EXPECT_EQ(r.CheckAuthor("alice", Writer(7, 9)), "");  // her contact-set writer: same participant
  const std::string forged = r.CheckAuthor("alice", Writer(8, 9));
  EXPECT_EQ(forged, "user 'alice' joined from participant 070000000000000000000007, this sample came from "
                    "participant 080000000000000000000008");
  InstanceKey last_byte_differs = Writer(7, 9);
  last_byte_differs[11] = 6;  // the prefix's last byte counts too
  EXPECT_NE(r.CheckAuthor("alice", last_byte_differs), "");
  EXPECT_EQ(r.CheckAuthor("mallory", Writer(8, 9)), "");  // not a member: nothing to compare with
  // Alice leaves and joins again with a new participant (a rejoin): her new one writes for her.
  ASSERT_TRUE(r.OnGone(Key(1), true));
  EXPECT_EQ(r.CheckAuthor("alice", Writer(8, 9)), "");
  r.OnInfo(Key(1), Writer(8, 1), Member{"s/alice", "alice", "haptic", "sim", 12});
  EXPECT_EQ(r.CheckAuthor("alice", Writer(8, 9)), "");
  EXPECT_NE(r.CheckAuthor("alice", Writer(7, 9)), "");  // the old participant no longer does
}

TEST(MemberRegistry, UnknownInstanceGoneIsIgnored) {
  MemberRegistry r;
  EXPECT_FALSE(r.OnGone(Key(9), true));
}

}  // namespace
}  // namespace handshare::server

namespace handshare::server {
namespace {

// A partition: alice's writer is lost (her member too), then matches again when the network
// heals. Fast DDS 2.9 does not deliver her transient-local member sample again, so the
// registry brings back what that writer had announced: one rejoin, no duplicate member.
TEST(MemberRegistry, AMemberLostWithItsWriterRejoinsOnceWhenTheWriterComesBack) {
  MemberRegistry r;
  const InstanceKey alice_key{1}, alice_writer{7}, bob_key{2}, bob_writer{8};
  ASSERT_TRUE(r.OnInfo(alice_key, alice_writer, Member{"s/alice", "alice", "haptic", "sim", 11}));
  ASSERT_TRUE(r.OnInfo(bob_key, bob_writer, Member{"s/bob", "bob", "haptic", "sim", 12}));
  ASSERT_EQ(r.OnWriterLost(alice_writer).size(), 1u);
  EXPECT_EQ(r.present().size(), 1u);
  // A writer that was never lost (bob's matching again, a new one) brings nothing back.
  EXPECT_TRUE(r.OnWriterRegained(bob_writer).empty());
  EXPECT_TRUE(r.OnWriterRegained(InstanceKey{9}).empty());
  const auto back = r.OnWriterRegained(alice_writer);
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].change, MemberChange::kJoined);
  EXPECT_EQ(back[0].member.user, "alice");
  EXPECT_EQ(r.present().size(), 2u);
  // Matched and regained liveliness both report it: still one alice.
  EXPECT_TRUE(r.OnWriterRegained(alice_writer).empty());
  EXPECT_FALSE(r.OnInfo(alice_key, alice_writer, Member{"s/alice", "alice", "haptic", "sim", 11}).has_value());
  EXPECT_EQ(r.present().size(), 2u);
  EXPECT_EQ(r.joined_total(), 3u);  // alice, bob, alice again
}

TEST(MemberRegistry, ACleanLeaveDoesNotComeBackWithItsWriter) {
  MemberRegistry r;
  const InstanceKey key{1}, writer{7};
  ASSERT_TRUE(r.OnInfo(key, writer, Member{"s/carol", "carol", "graphics", "", 13}));
  ASSERT_TRUE(r.OnGone(key, /*disposed=*/true));
  EXPECT_TRUE(r.OnWriterLost(writer).empty());
  EXPECT_TRUE(r.OnWriterRegained(writer).empty());
  EXPECT_TRUE(r.present().empty());
}

// A process restarted after a loss announces itself with a new writer: a normal join, and the
// old writer coming back later (it cannot, but a stale match might) adds no second member.
TEST(MemberRegistry, ARestartedMembersNewWriterJoinsAndTheOldOneBringsNothingBack) {
  MemberRegistry r;
  const InstanceKey key{1}, old_writer{7}, new_writer{8};
  ASSERT_TRUE(r.OnInfo(key, old_writer, Member{"s/dave", "dave", "haptic", "sim", 14}));
  ASSERT_EQ(r.OnWriterLost(old_writer).size(), 1u);
  ASSERT_TRUE(r.OnInfo(key, new_writer, Member{"s/dave", "dave", "haptic", "sim", 15}));
  EXPECT_TRUE(r.OnWriterRegained(old_writer).empty());
  EXPECT_EQ(r.present().size(), 1u);
}

}  // namespace
}  // namespace handshare::server
