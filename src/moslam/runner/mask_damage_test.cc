#include "moslam/runner/mask_damage.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/util/error.h"

namespace moslam::runner {
namespace {

cv::Mat Body() {
  cv::Mat m = cv::Mat::zeros(480, 640, CV_8UC1);
  m(cv::Rect(0, 100, 200, 300)).setTo(255);  // a body entering at the left border
  return m;
}

TEST(MaskDamage, ParsesEveryKeyAndNamesTheBadOne) {
  const MaskDamageOptions o =
      ParseMaskDamage("miss=0.2, border=40,erode=3,holes=0.1,radius=8,seed=7");
  EXPECT_DOUBLE_EQ(o.miss, 0.2);
  EXPECT_EQ(o.border_px, 40);
  EXPECT_EQ(o.erode_px, 3);
  EXPECT_DOUBLE_EQ(o.holes, 0.1);
  EXPECT_EQ(o.hole_radius_px, 8);
  EXPECT_EQ(o.seed, 7u);
  EXPECT_FALSE(ParseMaskDamage("").Any());
  try {
    ParseMaskDamage("mis=0.2");
    FAIL() << "no error for an unknown key";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'mis'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ParseMaskDamage("miss=1.5"), InputError);
  EXPECT_THROW(ParseMaskDamage("erode=2.5"), InputError);
  EXPECT_THROW(ParseMaskDamage("border"), InputError);
}

TEST(MaskDamage, EachKindDamagesAsItSays) {
  const cv::Mat body = Body();
  MaskDamageOptions border;
  border.border_px = 40;
  cv::Mat out = DamageMask(body, 0, border);
  EXPECT_EQ(out.at<uint8_t>(200, 39), 0);
  EXPECT_EQ(out.at<uint8_t>(200, 40), 255);
  EXPECT_EQ(cv::countNonZero(out), 160 * 300);

  MaskDamageOptions erode;
  erode.erode_px = 3;
  out = DamageMask(body, 0, erode);
  EXPECT_EQ(out.at<uint8_t>(200, 196), 255);
  EXPECT_EQ(out.at<uint8_t>(200, 197), 0);

  MaskDamageOptions holes;
  holes.holes = 0.2;
  out = DamageMask(body, 5, holes);
  const double kept = cv::countNonZero(out) / double(cv::countNonZero(body));
  EXPECT_GT(kept, 0.7);  // overlapping holes remove a little less than 20 %
  EXPECT_LT(kept, 0.9);
  // The same frame is damaged the same way every time; another frame differently.
  EXPECT_EQ(cv::countNonZero(DamageMask(body, 5, holes) != out), 0);
  EXPECT_GT(cv::countNonZero(DamageMask(body, 6, holes) != out), 0);

  MaskDamageOptions miss;
  miss.miss = 0.3;
  int missed = 0;
  for (int i = 0; i < 1000; ++i) missed += cv::countNonZero(DamageMask(body, i, miss)) == 0;
  EXPECT_NEAR(missed, 300, 60);
  EXPECT_TRUE(DamageMask(cv::Mat(), 0, miss).empty());
}

}  // namespace
}  // namespace moslam::runner
