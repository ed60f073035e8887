#include "handshare/common/latency_histogram.hpp"

#include <gtest/gtest.h>

namespace handshare::common {
namespace {

TEST(LatencyHistogram, QuantilesOfUniformMicroseconds) {
  LatencyHistogram h;
  for (int i = 0; i < 1000; ++i) h.Record(i + 0.5);  // 0.5 .. 999.5 us
  EXPECT_EQ(h.count(), 1000u);
  // 1 us bins below 1 ms: the quantile is the bin's upper edge, so within 1 us.
  EXPECT_NEAR(h.Quantile(0.5), 500.0, 1.0);
  EXPECT_NEAR(h.Quantile(0.99), 990.0, 1.0);
  EXPECT_DOUBLE_EQ(h.max_us(), 999.5);
  EXPECT_NEAR(h.mean_us(), 500.0, 1e-9);
}

TEST(LatencyHistogram, LargeValuesWithinOnePercent) {
  LatencyHistogram h;
  for (int i = 0; i < 99; ++i) h.Record(10.0);
  h.Record(50000.0);  // one 50 ms outlier
  EXPECT_NEAR(h.Quantile(0.5), 11.0, 1e-9);
  EXPECT_NEAR(h.Quantile(1.0), 50000.0, 500.0);
  EXPECT_DOUBLE_EQ(h.max_us(), 50000.0);
}

TEST(LatencyHistogram, EmptyAndNegative) {
  LatencyHistogram h;
  EXPECT_EQ(h.Quantile(0.5), 0.0);
  h.Record(-3.0);  // an early wake-up counts as zero jitter bin, never out of range
  EXPECT_EQ(h.count(), 1u);
  EXPECT_LE(h.Quantile(0.5), 1.0);
}

}  // namespace
}  // namespace handshare::common
