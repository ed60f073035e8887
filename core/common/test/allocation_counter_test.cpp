#include "handshare/testing/allocation_counter.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace handshare::testing {
namespace {

// The no-allocation tests of the haptic step are only as good as this counter.
TEST(AllocationCounter, CountsEveryNew) {
  const long before = AllocationCount();
  auto one = std::make_unique<int>(1);
  std::vector<double> many(16);
  EXPECT_EQ(AllocationCount() - before, 2);
  EXPECT_EQ(*one + static_cast<int>(many.size()), 17);
}

}  // namespace
}  // namespace handshare::testing
