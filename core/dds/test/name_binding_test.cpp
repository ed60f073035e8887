// NameBinding: a present user's name belongs to the participant that announced it.
#include "handshare/dds/name_binding.hpp"

#include <gtest/gtest.h>

namespace handshare::dds {
namespace {

// An endpoint of participant `participant` (its 12-byte prefix) with entity `entity`.
Guid Endpoint(std::uint8_t participant, std::uint8_t entity) {
  Guid g{};
  for (int i = 0; i < 12; ++i) g[i] = static_cast<std::uint8_t>(participant + i);
  g[15] = entity;
  return g;
}
// A member (its key hash): any 16 bytes that tell members apart.
Guid Instance(std::uint8_t n) { return Endpoint(static_cast<std::uint8_t>(100 + n), 0); }

TEST(NameBinding, OnlyTheAnnouncingParticipantWritesInAPresentUsersName) {
  NameBinding b;
  b.OnMember(Instance(1), "alice", Endpoint(7, 1));  // alice's member writer
  EXPECT_EQ(b.Check("alice", Endpoint(7, 9)), "");   // her contact-set writer: same participant
  const std::string forged = b.Check("alice", Endpoint(8, 9));
  EXPECT_NE(forged.find("user 'alice' joined from participant 0708090a0b0c0d0e0f101112"), std::string::npos) << forged;
  EXPECT_NE(forged.find("this sample came from participant 08090a0b0c0d0e0f10111213"), std::string::npos) << forged;
  Guid last_byte_differs = Endpoint(7, 9);
  last_byte_differs[11] ^= 1;  // the prefix's last byte: another participant
  EXPECT_NE(b.Check("alice", last_byte_differs), "");
  EXPECT_EQ(b.Check("bob", Endpoint(8, 9)), "");  // not announced: anybody's
}

TEST(NameBinding, ANameIsFreeAgainOnceItsMemberLeftOrItsWriterWasLost) {
  NameBinding b;
  b.OnMember(Instance(1), "alice", Endpoint(7, 1));
  b.OnMember(Instance(2), "bob", Endpoint(9, 1));
  b.OnMemberGone(Instance(1));
  EXPECT_EQ(b.Check("alice", Endpoint(8, 9)), "");
  EXPECT_NE(b.Check("bob", Endpoint(8, 9)), "");
  b.OnWriterLost(Endpoint(9, 1));
  EXPECT_EQ(b.Check("bob", Endpoint(8, 9)), "");
  EXPECT_EQ(b.size(), 0u);
}

TEST(NameBinding, APresentUsersDeviceIsKnownUntilTheyLeave) {
  NameBinding b;
  b.OnMember(Instance(1), "alice", Endpoint(7, 1), msg::NODE_HAPTIC, 0.0, "sim");
  b.OnMember(Instance(2), "bob", Endpoint(9, 1), msg::NODE_HAPTIC, 0.0, "hiro");
  b.OnMember(Instance(3), "screen", Endpoint(11, 1), msg::NODE_GRAPHICS, 30.0);
  EXPECT_EQ(b.DeviceOf("alice"), "sim");
  EXPECT_EQ(b.DeviceOf("bob"), "hiro");
  EXPECT_EQ(b.DeviceOf("screen"), "");
  EXPECT_EQ(b.DeviceOf("carol"), "");
  EXPECT_EQ(b.users(), (std::vector<std::string>{"alice", "bob", "screen"}));
  b.OnMemberGone(Instance(2));
  EXPECT_EQ(b.DeviceOf("bob"), "");
  EXPECT_EQ(b.users(), (std::vector<std::string>{"alice", "screen"}));
}

TEST(NameBinding, ThePresentViewersAndTheFastestFrameRate) {
  NameBinding b;
  b.OnMember(Instance(1), "alice", Endpoint(7, 1), msg::NODE_HAPTIC);
  EXPECT_EQ(b.viewers().count, 0);
  b.OnMember(Instance(2), "screen", Endpoint(8, 1), msg::NODE_GRAPHICS, 2.0);
  b.OnMember(Instance(3), "wall", Endpoint(9, 1), msg::NODE_GRAPHICS, 60.0);
  EXPECT_EQ(b.viewers().count, 2);
  EXPECT_DOUBLE_EQ(b.viewers().fastest_Hz, 60.0);
  b.OnWriterLost(Endpoint(9, 1));  // the wall screen was killed: the slower one sets the rate
  EXPECT_EQ(b.viewers().count, 1);
  EXPECT_DOUBLE_EQ(b.viewers().fastest_Hz, 2.0);
}

TEST(NameBinding, ANewAnnouncementOfAMemberMovesItsName) {
  NameBinding b;
  b.OnMember(Instance(1), "alice", Endpoint(7, 1));
  b.OnMember(Instance(1), "alice", Endpoint(8, 1));  // the same member, announced anew elsewhere
  EXPECT_EQ(b.Check("alice", Endpoint(8, 9)), "");
  EXPECT_NE(b.Check("alice", Endpoint(7, 9)), "");
}

}  // namespace
}  // namespace handshare::dds
