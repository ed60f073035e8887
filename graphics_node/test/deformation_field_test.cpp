#include "handshare/graphics/deformation_field.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace handshare::graphics {
namespace {

// Values go through float on the wire; the field keeps them exactly (float -> double).
Eigen::Vector3d F(float x, float y, float z) { return {x, y, z}; }

TEST(DeformationField, StartsAtZeroWithNoRevision) {
  const DeformationField field(5);
  EXPECT_EQ(field.vertex_count(), 5U);
  EXPECT_FALSE(field.revision().has_value());
  EXPECT_FALSE(field.displaced());
  for (const auto& u : field.u_W_m()) EXPECT_TRUE(u.isZero(0.0));
}

TEST(DeformationField, KeyframeZeroesThenSetsAndDeltasOnlyTouchTheirNodes) {
  DeformationField field(6);
  const std::vector<std::uint32_t> ids1 = {1, 4};
  const std::vector<float> u1 = {0.001F, 0.0F, -0.002F, 0.0F, 0.003F, 0.0F};
  ASSERT_TRUE(field.Apply(1, true, ids1, u1));
  EXPECT_EQ(field.revision(), 1U);
  EXPECT_TRUE(field.displaced());
  EXPECT_EQ(field.u_W_m()[1], F(0.001F, 0.0F, -0.002F));
  EXPECT_EQ(field.u_W_m()[4], F(0.0F, 0.003F, 0.0F));
  EXPECT_TRUE(field.u_W_m()[0].isZero(0.0));

  // A delta changes node 4 and adds node 2; node 1 keeps its value.
  const std::vector<std::uint32_t> ids2 = {4, 2};
  const std::vector<float> u2 = {0.0F, 0.005F, 0.0F, -0.001F, -0.001F, -0.001F};
  ASSERT_TRUE(field.Apply(2, false, ids2, u2));
  EXPECT_EQ(field.revision(), 2U);
  EXPECT_EQ(field.u_W_m()[1], F(0.001F, 0.0F, -0.002F));
  EXPECT_EQ(field.u_W_m()[4], F(0.0F, 0.005F, 0.0F));
  EXPECT_EQ(field.u_W_m()[2], F(-0.001F, -0.001F, -0.001F));

  // A new keyframe that lists only node 3: everything else goes back to zero.
  const std::vector<std::uint32_t> ids3 = {3};
  const std::vector<float> u3 = {0.0F, 0.0F, 0.004F};
  ASSERT_TRUE(field.Apply(3, true, ids3, u3));
  for (std::size_t v = 0; v < 6; ++v) {
    if (v == 3) {
      EXPECT_EQ(field.u_W_m()[v], F(0.0F, 0.0F, 0.004F));
    } else {
      EXPECT_TRUE(field.u_W_m()[v].isZero(0.0)) << "vertex " << v;
    }
  }
  EXPECT_EQ(field.stats().samples, 3U);
  EXPECT_EQ(field.stats().keyframes, 2U);

  // An empty keyframe says "everything at rest".
  ASSERT_TRUE(field.Apply(4, true, {}, {}));
  EXPECT_FALSE(field.displaced());
  EXPECT_EQ(field.revision(), 4U);
}

TEST(DeformationField, SplitSamplesOfOneKeyframeRevisionAddUp) {
  DeformationField field(8);
  const std::vector<std::uint32_t> before = {7};
  const std::vector<float> u_before = {1.0F, 1.0F, 1.0F};
  ASSERT_TRUE(field.Apply(9, false, before, u_before));
  // Keyframe revision 10 in two samples: the first zeroes (node 7 goes), the second must not
  // zero what the first set.
  const std::vector<std::uint32_t> a = {0, 1, 2};
  const std::vector<float> u_a = {0.1F, 0, 0, 0.2F, 0, 0, 0.3F, 0, 0};
  const std::vector<std::uint32_t> b = {5, 6};
  const std::vector<float> u_b = {0, 0.5F, 0, 0, 0.6F, 0};
  ASSERT_TRUE(field.Apply(10, true, a, u_a));
  ASSERT_TRUE(field.Apply(10, true, b, u_b));
  EXPECT_EQ(field.u_W_m()[0], F(0.1F, 0, 0));
  EXPECT_EQ(field.u_W_m()[1], F(0.2F, 0, 0));
  EXPECT_EQ(field.u_W_m()[2], F(0.3F, 0, 0));
  EXPECT_EQ(field.u_W_m()[5], F(0, 0.5F, 0));
  EXPECT_EQ(field.u_W_m()[6], F(0, 0.6F, 0));
  EXPECT_TRUE(field.u_W_m()[7].isZero(0.0)) << "the keyframe's first sample zeroes the field";
  EXPECT_EQ(field.stats().keyframes, 1U) << "one keyframe revision zeroes once";
}

TEST(DeformationField, IdsBeyondTheVertexCountAreIgnoredAndCounted) {
  DeformationField field(3);
  const std::vector<std::uint32_t> ids = {0, 3, 1000000, 2};
  const std::vector<float> u = {1, 0, 0, 2, 0, 0, 3, 0, 0, 4, 0, 0};
  ASSERT_TRUE(field.Apply(1, true, ids, u));
  EXPECT_EQ(field.stats().ids_out_of_range, 2U);
  EXPECT_EQ(field.u_W_m()[0], F(1, 0, 0));
  EXPECT_TRUE(field.u_W_m()[1].isZero(0.0));
  EXPECT_EQ(field.u_W_m()[2], F(4, 0, 0)) << "entries after a bad id still apply";
}

TEST(DeformationField, NonFiniteEntriesAndMalformedSamplesChangeNothing) {
  DeformationField field(3);
  const std::vector<std::uint32_t> ids = {0, 1};
  const std::vector<float> u = {0.5F, 0, 0, 0.25F, 0, 0};
  ASSERT_TRUE(field.Apply(1, true, ids, u));

  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> bad = {nan, 0, 0, 0, inf, 0};
  ASSERT_TRUE(field.Apply(2, false, ids, bad));
  EXPECT_EQ(field.stats().nonfinite, 2U);
  EXPECT_EQ(field.u_W_m()[0], F(0.5F, 0, 0)) << "the last good value stays";
  EXPECT_EQ(field.u_W_m()[1], F(0.25F, 0, 0));

  // Two ids but four values: the whole sample is rejected, even its keyframe flag.
  const std::vector<float> short_u = {1, 1, 1, 1};
  EXPECT_FALSE(field.Apply(3, true, ids, short_u));
  EXPECT_EQ(field.stats().malformed, 1U);
  EXPECT_EQ(field.revision(), 2U);
  EXPECT_EQ(field.u_W_m()[0], F(0.5F, 0, 0));
}

TEST(DeformationField, SettingANodeBackToZeroClearsDisplaced) {
  DeformationField field(2);
  const std::vector<std::uint32_t> ids = {1};
  const std::vector<float> u = {0, 0, 0.001F};
  ASSERT_TRUE(field.Apply(1, false, ids, u));
  EXPECT_TRUE(field.displaced());
  const std::vector<float> zero = {0, 0, 0};
  ASSERT_TRUE(field.Apply(2, false, ids, zero));
  EXPECT_FALSE(field.displaced());
}

TEST(DeformationField, ResetForgetsTheRevisionSoARestartedWriterKeyframes) {
  DeformationField field(4);
  const std::vector<std::uint32_t> ids = {2};
  const std::vector<float> u = {0, 0.01F, 0};
  ASSERT_TRUE(field.Apply(1, true, ids, u));
  const std::uint64_t version = field.version();
  field.Reset();
  EXPECT_GT(field.version(), version);
  EXPECT_FALSE(field.revision().has_value());
  EXPECT_FALSE(field.displaced());
  EXPECT_TRUE(field.u_W_m()[2].isZero(0.0));

  // Without Reset, a writer that starts again at revision 1 still has its keyframe applied as
  // one, since 1 differs from the last revision seen.
  ASSERT_TRUE(field.Apply(5, false, ids, u));
  const std::vector<std::uint32_t> other = {0};
  ASSERT_TRUE(field.Apply(1, true, other, u));
  EXPECT_TRUE(field.u_W_m()[2].isZero(0.0));
  EXPECT_EQ(field.u_W_m()[0], F(0, 0.01F, 0));
}

}  // namespace
}  // namespace handshare::graphics
