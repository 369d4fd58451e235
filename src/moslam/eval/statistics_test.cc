#include "moslam/eval/statistics.h"

#include <cmath>

#include <gtest/gtest.h>

namespace moslam::eval {
namespace {

TEST(Statistics, MatchesNumpyDefinitions) {
  const ErrorStatistics s = ComputeStatistics({4.0, 1.0, 3.0, 2.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);           // mean of the two middle values
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));  // population, ddof = 0
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
}

TEST(Statistics, OddCountMedianIsTheMiddleValue) {
  EXPECT_DOUBLE_EQ(Median({5.0, 1.0, 9.0}), 5.0);
  EXPECT_DOUBLE_EQ(ComputeStatistics({5.0, 1.0, 9.0, 7.0, 2.0}).median, 5.0);
}

TEST(Statistics, StdKeepsDigitsForLargeMeans) {
  const ErrorStatistics s = ComputeStatistics({1e8 + 1, 1e8 - 1});
  EXPECT_DOUBLE_EQ(s.std, 1.0);
}

TEST(Statistics, EmptyHasCountZero) {
  const ErrorStatistics s = ComputeStatistics({});
  EXPECT_EQ(s.count, 0u);
  EXPECT_EQ(s.rmse, 0.0);
  EXPECT_EQ(Median({}), 0.0);
}

TEST(Statistics, SeriesKeepsValues) {
  const ErrorSeries series = MakeSeries({3.0, 4.0});
  ASSERT_EQ(series.values.size(), 2u);
  EXPECT_DOUBLE_EQ(series.stats.rmse, std::sqrt(12.5));
}

}  // namespace
}  // namespace moslam::eval
