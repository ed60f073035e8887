// The contact codec: the one contact type through the IDL's finger and back.
#include "handshare/dds/contact_codec.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "handshare/dds/sample_checks.hpp"
#include "handshare/dds/serialization.hpp"

namespace handshare::dds {
namespace {

contact::FingerContact APress() {
  contact::FingerContact c;
  c.finger = 3;
  c.object = 11;  // the sender's index: does not travel
  c.node = 417;
  c.p_OC_m = {0.012, -0.034, 0.056};
  c.n_O = {0.0, 0.6, 0.8};
  c.p_OE_m = {0.012, -0.0292, 0.0624};
  c.u_O_m = {0.0004, -0.0012, -0.0016};
  c.f_O_N = {0.05, -0.36, -0.48};
  c.depth_m = 0.002;
  return c;
}

TEST(ContactCodec, AContactRoundTripsThroughTheWireBitForBit) {
  const contact::FingerContact sent = APress();
  msg::ContactSet set;
  set.session("s");
  set.user("alice");
  EncodeFingerContact(sent, "tail", 0.008, SampleBounds{}.max_displacement_m, set.fingers()[3]);
  // Through the bytes a receiver gets.
  msg::ContactSet received;
  Deserialize(Serialize(set), received);
  EXPECT_EQ(CheckContactSet(received, "s"), "");
  const auto& f = received.fingers()[3];
  EXPECT_TRUE(f.active());
  EXPECT_EQ(f.object_id().to_string(), "tail");
  EXPECT_EQ(f.radius_m(), 0.008);
  contact::FingerContact got;
  ASSERT_TRUE(DecodeFingerContact(f, 3, 5, got));  // the receiver's own index for "tail"
  EXPECT_EQ(got.finger, 3);
  EXPECT_EQ(got.object, 5);
  EXPECT_EQ(got.node, sent.node);
  EXPECT_EQ(got.p_OC_m, sent.p_OC_m);
  EXPECT_EQ(got.n_O, sent.n_O);
  EXPECT_EQ(got.p_OE_m, sent.p_OE_m);
  EXPECT_EQ(got.u_O_m, sent.u_O_m);
  EXPECT_EQ(got.f_O_N, sent.f_O_N);  // the force on the object, both sides
  EXPECT_EQ(got.depth_m, sent.depth_m);
}

TEST(ContactCodec, AnInactiveFingerTravelsEmptyAndDecodesToNothing) {
  contact::FingerContact none = APress();
  none.object = -1;
  msg::FingerContact f;
  EncodeFingerContact(APress(), "tail", 0.008, 0.1, f);  // a finger that touched before
  EncodeFingerContact(none, "tail", 0.008, 0.1, f);
  EXPECT_FALSE(f.active());
  EXPECT_EQ(f.object_id().to_string(), "");
  EXPECT_EQ(f.surface_node(), -1);
  EXPECT_EQ(f.u_O_m(), (contact::Vec3{0.0, 0.0, 0.0}));
  EXPECT_EQ(f.f_O_N(), (contact::Vec3{0.0, 0.0, 0.0}));
  contact::FingerContact got = APress();
  EXPECT_FALSE(DecodeFingerContact(f, 2, 5, got));
  EXPECT_FALSE(got.active());
  EXPECT_EQ(got.finger, 2);
  // An active finger on an object the receiver does not have (another world): nothing either.
  EncodeFingerContact(APress(), "comet", 0.008, 0.1, f);
  EXPECT_FALSE(DecodeFingerContact(f, 2, -1, got));
  EXPECT_FALSE(got.active());
}

// A fingertip pushed far through an object (after a stall) would have every receiver drop the
// whole set; it goes out at the bound, in its own direction, and the checks accept it.
TEST(ContactCodec, ADisplacementBeyondTheBoundGoesOutClampedInItsDirection) {
  contact::FingerContact c = APress();
  c.u_O_m = {0.05, 0.0, -0.117};
  c.depth_m = 0.117;
  msg::ContactSet set;
  set.session("s");
  set.user("alice");
  EncodeFingerContact(c, "tail", 0.008, 0.1, set.fingers()[0]);
  EXPECT_EQ(CheckContactSet(set, "s"), "");
  const auto& u = set.fingers()[0].u_O_m();
  EXPECT_NEAR(std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]), 0.1, 1e-12);
  EXPECT_NEAR(u[0] / u[2], 0.05 / -0.117, 1e-12);
  EXPECT_DOUBLE_EQ(set.fingers()[0].depth_m(), 0.1);
}

}  // namespace
}  // namespace handshare::dds
