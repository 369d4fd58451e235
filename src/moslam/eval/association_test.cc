#include "moslam/eval/association.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/util/error.h"

namespace moslam::eval {
namespace {

using ::testing::ElementsAre;

TEST(AssociateGreedy, TakesSmallestDifferencesFirstAndEachStampOnce) {
  const std::vector<double> gt = {1.00, 1.10, 1.20};
  const std::vector<double> est = {1.005, 1.012, 1.19, 1.5};
  const Association a = AssociateGreedy(gt, est, 0.0, 0.02);
  EXPECT_THAT(a.gt, ElementsAre(0u, 2u));
  EXPECT_THAT(a.est, ElementsAre(0u, 2u));  // 1.012 lost to 1.005; 1.5 too far
}

TEST(AssociateGreedy, ContestedStampGoesToTheCloserPartner) {
  const Association a = AssociateGreedy({1.0, 1.01}, {1.008}, 0.0, 0.02);
  EXPECT_THAT(a.gt, ElementsAre(1u));
  EXPECT_THAT(a.est, ElementsAre(0u));
}

TEST(AssociateGreedy, MaxDtIsStrictAndOffsetMovesTheEstimate) {
  EXPECT_EQ(AssociateGreedy({0.0}, {0.5}, 0.0, 0.5).size(), 0u);  // |0 - 0.5| < 0.5 fails
  EXPECT_EQ(AssociateGreedy({0.0}, {0.5}, 0.0, 0.5000001).size(), 1u);
  const Association a = AssociateGreedy({10.0}, {12.0, 13.0}, -3.0, 0.01);
  EXPECT_THAT(a.est, ElementsAre(1u));  // 13 - 3 = 10
}

TEST(AssociateGreedy, ResultSortedByGroundTruthStamp) {
  // Taken in the order gt 2.0 (difference 0), then 1.0 and 3.0; returned by gt stamp.
  const Association a = AssociateGreedy({1.0, 2.0, 3.0}, {1.001, 2.0, 2.999}, 0.0, 0.01);
  EXPECT_THAT(a.gt, ElementsAre(0u, 1u, 2u));
  EXPECT_THAT(a.est, ElementsAre(0u, 1u, 2u));
}

TEST(AssociateGreedy, RepeatedStampUsesTheLaterPose) {
  const Association a = AssociateGreedy({1.0, 2.0, 2.0, 3.0}, {2.001}, 0.0, 0.02);
  EXPECT_THAT(a.gt, ElementsAre(2u));
}

TEST(AssociateNearest, ShorterTrajectoryTakesItsNearestPartnerInclusively) {
  // The estimate is shorter: each estimate stamp finds its nearest gt stamp; <= max_dt.
  const std::vector<double> gt = {0.0, 0.1, 0.2, 0.3, 0.4};
  const Association a = AssociateNearest(gt, {0.104, 0.36, 0.5}, 0.0, 0.1);
  EXPECT_THAT(a.est, ElementsAre(0u, 1u, 2u));
  EXPECT_THAT(a.gt, ElementsAre(1u, 4u, 4u));  // gt 0.4 used twice, as evo allows
  EXPECT_EQ(AssociateNearest(gt, {0.55}, 0.0, 0.1).size(), 0u);
}

TEST(AssociateNearest, LongerEstimateIsSearchedFromTheGroundTruth) {
  const Association a = AssociateNearest({1.0, 2.0}, {0.9, 1.02, 1.5, 1.98, 2.5}, 0.0, 0.05);
  EXPECT_THAT(a.gt, ElementsAre(0u, 1u));
  EXPECT_THAT(a.est, ElementsAre(1u, 3u));
}

TEST(AssociateNearest, TiesAndRepeatsResolveToTheFirstIndexLikeArgmin) {
  EXPECT_THAT(AssociateNearest({1.0, 2.0, 3.0}, {1.5}, 0.0, 1.0).gt, ElementsAre(0u));
  EXPECT_THAT(AssociateNearest({1.0, 2.0, 2.0, 3.0}, {2.001}, 0.0, 0.1).gt, ElementsAre(1u));
}

TEST(AssociateNearest, OffsetIsAddedToTheEstimate) {
  const Association a = AssociateNearest({10.0, 11.0, 12.0}, {5.0}, 6.0, 0.01);
  EXPECT_THAT(a.gt, ElementsAre(1u));
}

TEST(AssociateByIndex, NeedsEqualLengths) {
  EXPECT_EQ(AssociateByIndex(3, 3).size(), 3u);
  EXPECT_THROW(AssociateByIndex(3, 4), InputError);
}

}  // namespace
}  // namespace moslam::eval
