#include "common/demand.hpp"

#include <gtest/gtest.h>

namespace {

int checked_half(int even) {
  MCG_DEMAND(even % 2 == 0);
  return even / 2;
}

TEST(Demand, PassesThroughWhenTheConditionHolds) { EXPECT_EQ(checked_half(8), 4); }

// The build CI gates on is RelWithDebInfo (NDEBUG): the check must still stop the program there.
TEST(DemandDeathTest, StopsWithTheConditionAndPlaceInEveryBuildType) {
  EXPECT_DEATH(checked_half(3), "mcg: internal error: even % 2 == 0 failed at .*test_common_demand.cpp:8");
}

}  // namespace
