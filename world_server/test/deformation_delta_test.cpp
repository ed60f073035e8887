#include "handshare/world_server/deformation_delta.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace handshare::server {
namespace {

using namespace std::chrono_literals;
using Time = DeformationDelta::Time;

Time At(std::chrono::nanoseconds t) { return Time{} + t; }

// A graphics node applying samples by the documented receiver rule: independent of the
// sender's bookkeeping.
struct Receiver {
  explicit Receiver(std::size_t n) : u(3 * n, 0.0) {}
  void Apply(std::span<const DeformationSample> samples) {
    for (const auto& s : samples) {
      EXPECT_EQ(s.u_W_m.size(), 3 * s.node_ids.size());
      EXPECT_EQ(s.surface_node_count, u.size() / 3);
      if (s.keyframe && s.revision != last_keyframe) {
        std::fill(u.begin(), u.end(), 0.0);
        last_keyframe = s.revision;
      }
      for (std::size_t i = 0; i < s.node_ids.size(); ++i) {
        for (int k = 0; k < 3; ++k) u[3 * s.node_ids[i] + k] = s.u_W_m[3 * i + k];
      }
    }
  }
  std::vector<double> u;
  std::uint32_t last_keyframe = 0;
};

std::size_t Nodes(std::span<const DeformationSample> samples) {
  std::size_t n = 0;
  for (const auto& s : samples) n += s.node_ids.size();
  return n;
}

TEST(DeformationDelta, TheFirstUpdateIsAKeyframeOfTheDisplacedNodes) {
  DeformationDelta d(4);
  std::vector<double> u(12, 0.0);
  u[3 * 2 + 1] = -0.003;  // node 2 pressed in by 3 mm
  const auto out = d.Update(u, At(0s));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_TRUE(out[0].keyframe);
  EXPECT_EQ(out[0].revision, 1u);
  EXPECT_EQ(out[0].surface_node_count, 4u);
  ASSERT_EQ(out[0].node_ids, std::vector<std::uint32_t>{2});
  EXPECT_FLOAT_EQ(out[0].u_W_m[1], -0.003f);
}

TEST(DeformationDelta, OnlyNodesThatMovedMoreThanTheThresholdAndNothingAtRest) {
  DeformationDeltaConfig config;
  config.threshold_m = 1e-4;
  DeformationDelta d(5, config);
  std::vector<double> u(15, 0.0);
  ASSERT_EQ(d.Update(u, At(0ms)).size(), 1u);  // keyframe (empty: all at rest)
  EXPECT_TRUE(d.Update(u, At(100ms)).empty());  // nothing changed: nothing sent
  u[3 * 1 + 0] = 0.5e-4;                         // below the threshold
  EXPECT_TRUE(d.Update(u, At(200ms)).empty());
  u[3 * 1 + 0] = 1.5e-4;  // now above it (against the last sent value, 0)
  u[3 * 4 + 2] = 2e-3;
  auto out = d.Update(u, At(300ms));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_FALSE(out[0].keyframe);
  EXPECT_EQ(out[0].revision, 2u);
  EXPECT_EQ(out[0].node_ids, (std::vector<std::uint32_t>{1, 4}));
  // Slow creep: 0.6e-4 per step is sent every second step, when the sum passes the threshold.
  u[3 * 4 + 2] += 0.6e-4;
  EXPECT_TRUE(d.Update(u, At(400ms)).empty());
  u[3 * 4 + 2] += 0.6e-4;
  out = d.Update(u, At(500ms));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].node_ids, std::vector<std::uint32_t>{4});
}

TEST(DeformationDelta, LargeUpdatesAreSplitAtTheSampleCapacity) {
  const std::size_t n = 10000;
  DeformationDelta d(n);  // 4096 nodes per sample, as the IDL allows
  std::vector<double> u(3 * n, 0.01);
  const auto out = d.Update(u, At(0s));
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].node_ids.size(), 4096u);
  EXPECT_EQ(out[1].node_ids.size(), 4096u);
  EXPECT_EQ(out[2].node_ids.size(), 10000u - 2 * 4096u);
  for (const auto& s : out) {
    EXPECT_TRUE(s.keyframe);
    EXPECT_EQ(s.revision, 1u);
    EXPECT_LE(s.u_W_m.size(), 12288u);  // the IDL's bound on u_W_m
  }
  EXPECT_EQ(out[1].node_ids.front(), 4096u);
  EXPECT_EQ(out[2].node_ids.back(), 9999u);
}

// An object pressed for 5 s at 60 Hz, then left alone: keyframes every 2 s while it changes,
// one more after it stops at most, then silence.
TEST(DeformationDelta, PeriodicKeyframesOnlyWhileTheObjectChanges) {
  DeformationDelta d(100);
  Receiver r(100);
  std::vector<double> u(300, 0.0);
  const auto tick = std::chrono::nanoseconds(1'000'000'000 / 60);
  std::vector<double> keyframe_times, send_times;
  for (int k = 0; k < 600; ++k) {  // 10 s
    const Time now = At(k * tick);
    const double t = std::chrono::duration<double>(now - At(0s)).count();
    if (t < 5.0) {
      for (std::size_t i = 0; i < 100; ++i) u[3 * i + 2] = -0.002 * std::sin(t + 0.01 * static_cast<double>(i));
    }
    const auto out = d.Update(u, now);
    r.Apply(out);
    if (!out.empty()) send_times.push_back(t);
    if (!out.empty() && out[0].keyframe) keyframe_times.push_back(t);
  }
  // t = 0 (first), 2, 4 while moving, then one at 6 s (changes since 4 s), then nothing. The
  // period counts from the last keyframe's tick, so each may come one 60 Hz tick late.
  ASSERT_EQ(keyframe_times.size(), 4u);
  EXPECT_NEAR(keyframe_times[1], 2.0, 0.035);
  EXPECT_NEAR(keyframe_times[2], 4.0, 0.07);
  EXPECT_NEAR(keyframe_times[3], 6.0, 0.1);
  EXPECT_EQ(send_times.back(), keyframe_times[3]);
  for (std::size_t i = 0; i < u.size(); ++i) EXPECT_NEAR(r.u[i], u[i], 1e-4) << i;
}

TEST(DeformationDelta, ANewReaderGetsAKeyframeEvenAtRest) {
  DeformationDelta d(3);
  std::vector<double> u = {0.001, 0, 0, 0, 0, 0, 0, 0, 0.002};
  d.Update(u, At(0s));
  EXPECT_TRUE(d.Update(u, At(1s)).empty());
  d.RequestKeyframe();
  const auto out = d.Update(u, At(2s));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_TRUE(out[0].keyframe);
  EXPECT_EQ(out[0].node_ids, (std::vector<std::uint32_t>{0, 2}));
  EXPECT_TRUE(d.Update(u, At(3s)).empty());
  EXPECT_TRUE(d.Update(u, At(10s)).empty());  // unchanged since that keyframe: no periodic one
  EXPECT_EQ(d.keyframes_sent(), 2u);
}

TEST(DeformationDelta, KeyframesCanCarryEveryNode) {
  DeformationDeltaConfig config;
  config.keyframe_all_nodes = true;
  DeformationDelta d(3, config);
  const std::vector<double> u(9, 0.0);
  const auto out = d.Update(u, At(0s));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].node_ids, (std::vector<std::uint32_t>{0, 1, 2}));
}

TEST(DeformationDelta, CallsFasterThanTheMinimumPeriodKeepTheirChangesForLater) {
  DeformationDelta d(1);  // min period 1/60 s
  std::vector<double> u = {0, 0, 0};
  d.Update(u, At(0ms));
  u[0] = 0.01;
  EXPECT_TRUE(d.Update(u, At(8ms)).empty());  // 120 Hz: too soon
  const auto out = d.Update(u, At(17ms));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].node_ids, std::vector<std::uint32_t>{0});
}

// Random displacements, keyframe requests and splits (fixed seed): the receiver is always within
// the threshold of the truth and equals what the sender believes it holds.
TEST(DeformationDelta, TheReceiverStaysWithinTheThreshold) {
  DeformationDeltaConfig config;
  config.threshold_m = 2e-4;
  config.max_nodes_per_sample = 7;
  config.keyframe_period = 500ms;
  const std::size_t n = 50;
  DeformationDelta d(n, config);
  Receiver r(n);
  std::mt19937 rng(11);
  std::normal_distribution<double> step(0.0, 1e-4);
  std::uniform_int_distribution<int> pick(0, 9);
  std::vector<double> u(3 * n, 0.0);
  std::size_t sent_nodes = 0, max_samples = 0;
  for (int k = 0; k < 2000; ++k) {
    for (auto& x : u) {
      if (pick(rng) < 3) x += step(rng);  // some nodes move each tick
      if (pick(rng) == 0 && k % 97 == 0) x = 0.0;  // and some snap back
    }
    if (k % 211 == 0) d.RequestKeyframe();
    const auto out = d.Update(u, At(k * 20ms));
    for (const auto& s : out) EXPECT_LE(s.node_ids.size(), 7u);
    max_samples = std::max(max_samples, out.size());
    sent_nodes += Nodes(out);
    r.Apply(out);
    for (std::size_t i = 0; i < n; ++i) {
      const double dx = r.u[3 * i] - u[3 * i], dy = r.u[3 * i + 1] - u[3 * i + 1], dz = r.u[3 * i + 2] - u[3 * i + 2];
      // threshold, plus float rounding of the sent value (|u| < 1 cm: < 1e-9 m)
      ASSERT_LE(std::sqrt(dx * dx + dy * dy + dz * dz), config.threshold_m + 1e-9) << "tick " << k << " node " << i;
      for (int c = 0; c < 3; ++c) ASSERT_EQ(r.u[3 * i + c], d.sent()[3 * i + c]);
    }
  }
  EXPECT_GT(max_samples, 1u);             // splits happened
  EXPECT_LT(sent_nodes, 2000u * n / 2);   // and deltas are much smaller than full frames
}

TEST(DeformationDelta, NonFiniteDisplacementsAreSkippedAndCounted) {
  DeformationDelta d(2);
  std::vector<double> u = {0.001, 0, 0, std::numeric_limits<double>::quiet_NaN(), 0, 0};
  const auto out = d.Update(u, At(0s));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].node_ids, std::vector<std::uint32_t>{0});
  EXPECT_EQ(d.nonfinite_skipped(), 1u);
}

TEST(DeformationDelta, BadArgumentsAreRefused) {
  EXPECT_THROW(DeformationDelta(0), std::invalid_argument);
  DeformationDeltaConfig bad;
  bad.threshold_m = 0.0;
  EXPECT_THROW(DeformationDelta(3, bad), std::invalid_argument);
  DeformationDelta d(3);
  const std::vector<double> u(8, 0.0);
  EXPECT_THROW(d.Update(u, At(0s)), std::invalid_argument);
}

TEST(DeformationDelta, StorageIsSizedOnceAndReused) {
  const std::size_t n = 5000;
  DeformationDelta d(n);
  std::vector<double> u(3 * n, 0.01);
  auto out = d.Update(u, At(0s));
  ASSERT_EQ(out.size(), 2u);
  const auto* ids = out[1].node_ids.data();
  const auto* values = out[1].u_W_m.data();
  for (int k = 1; k < 20; ++k) {
    for (auto& x : u) x = 0.01 * (k % 2 ? -1 : 1);
    out = d.Update(u, At(k * 1s));
    ASSERT_EQ(out.size(), 2u);
    EXPECT_EQ(out[1].node_ids.data(), ids);  // no reallocation
    EXPECT_EQ(out[1].u_W_m.data(), values);
  }
}

}  // namespace
}  // namespace handshare::server
