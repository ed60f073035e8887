#include "handshare/world/grasp.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace handshare::world {
namespace {

FingerForce F(double x, double y, double z) { return FingerForce{true, {x, y, z}}; }

TEST(IsGrasp, TwoOrMoreFingersPushingAgainstEachOther) {
  const FingerForce pinch[5] = {F(1, 0, 0), F(-1, 0, 0), {}, {}, {}};
  EXPECT_TRUE(IsGrasp(pinch, 5));
  const FingerForce push[5] = {F(1, 0, 0), F(1, 0.1, 0), F(0.9, 0, 0.2), {}, {}};  // one side only
  EXPECT_FALSE(IsGrasp(push, 5));
  const FingerForce one[5] = {F(1, 0, 0), {}, {}, {}, {}};
  EXPECT_FALSE(IsGrasp(one, 5));
  const FingerForce weak[5] = {F(1, 0, 0), F(-0.01, 0, 0), {}, {}, {}};
  EXPECT_FALSE(IsGrasp(weak, 5));
  // Tripod: three forces 120 degrees apart, each pair beyond 100 degrees.
  const double c = std::cos(2.0 * M_PI / 3.0), s = std::sin(2.0 * M_PI / 3.0);
  const FingerForce tripod[5] = {F(1, 0, 0), F(c, s, 0), F(c, -s, 0), {}, {}};
  EXPECT_TRUE(IsGrasp(tripod, 5));
  EXPECT_FALSE(IsGrasp(tripod, 5, 0.05, 2.2));  // 126 degrees asked for: not a grasp
  FingerForce inactive[5] = {F(1, 0, 0), F(-1, 0, 0), {}, {}, {}};
  inactive[1].active = false;
  EXPECT_FALSE(IsGrasp(inactive, 5));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const FingerForce broken[5] = {F(nan, 0, 0), F(-1, 0, 0), {}, {}, {}};
  EXPECT_FALSE(IsGrasp(broken, 5));
}

}  // namespace
}  // namespace handshare::world
