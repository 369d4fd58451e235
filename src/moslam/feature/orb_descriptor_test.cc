#include "moslam/feature/orb_descriptor.h"

#include <bitset>
#include <cmath>
#include <cstdint>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "moslam/feature/orb_pattern.h"
#include "moslam/feature/test_images.h"

namespace moslam::feature {
namespace {

int Hamming(const uint8_t* a, const uint8_t* b) {
  int bits = 0;
  for (int i = 0; i < kOrbDescriptorBytes; ++i) bits += std::bitset<8>(a[i] ^ b[i]).count();
  return bits;
}

double AngleDifference(double a, double b) {
  const double d = std::fmod(std::fabs(a - b), 360.0);
  return std::min(d, 360.0 - d);
}

TEST(OrbPattern, IsThePublishedConstant) {
  // First and last tests of the ORB pattern (Rublee et al. 2011; OpenCV's bit_pattern_31_).
  EXPECT_EQ(kOrbPattern[0][0], 8);
  EXPECT_EQ(kOrbPattern[0][1], -3);
  EXPECT_EQ(kOrbPattern[0][2], 9);
  EXPECT_EQ(kOrbPattern[0][3], 5);
  EXPECT_EQ(kOrbPattern[255][0], -1);
  EXPECT_EQ(kOrbPattern[255][1], -6);
  EXPECT_EQ(kOrbPattern[255][2], 0);
  EXPECT_EQ(kOrbPattern[255][3], -11);
  int sum = 0;
  for (const auto& test : kOrbPattern) {
    for (const int8_t v : test) {
      EXPECT_GE(v, -13);
      EXPECT_LE(v, 12);
      sum += v;
    }
  }
  EXPECT_EQ(sum, -406);  // checksum of all 1024 numbers
}

TEST(CircularPatch, IsOrbsSymmetricDisk) {
  const auto widths = CircularPatchHalfWidths();
  const std::array<int, 16> orb = {15, 15, 15, 15, 14, 14, 14, 13, 13, 12, 11, 10, 9, 8, 6, 3};
  for (int v = 0; v <= kOrbHalfPatch; ++v) EXPECT_EQ(widths[v], orb[v]) << "row " << v;
  // Symmetric under swapping u and v: (u, v) inside <=> (v, u) inside.
  for (int u = 0; u <= kOrbHalfPatch; ++u) {
    for (int v = 0; v <= kOrbHalfPatch; ++v) {
      EXPECT_EQ(u <= widths[v], v <= widths[u]) << u << "," << v;
    }
  }
}

// Plain-loop moments in double precision, as the reference.
double ReferenceAngle(const cv::Mat& image, int x, int y) {
  const auto widths = CircularPatchHalfWidths();
  double m10 = 0, m01 = 0;
  for (int v = -kOrbHalfPatch; v <= kOrbHalfPatch; ++v) {
    for (int u = -widths[std::abs(v)]; u <= widths[std::abs(v)]; ++u) {
      const double value = image.at<uint8_t>(y + v, x + u);
      m10 += u * value;
      m01 += v * value;
    }
  }
  double angle = std::atan2(m01, m10) * 180.0 / CV_PI;
  return angle < 0 ? angle + 360.0 : angle;
}

TEST(IntensityCentroidAngle, MatchesPlainMoments) {
  const cv::Mat image = test::TexturedImage(200, 150, 11);
  std::mt19937 rng(12);
  for (int i = 0; i < 500; ++i) {
    const int x = kOrbEdgeMargin + static_cast<int>(rng() % (200 - 2 * kOrbEdgeMargin));
    const int y = kOrbEdgeMargin + static_cast<int>(rng() % (150 - 2 * kOrbEdgeMargin));
    const float angle = IntensityCentroidAngle(image, x, y);
    EXPECT_GE(angle, 0.0f);
    EXPECT_LT(angle, 360.0f);
    EXPECT_LT(AngleDifference(angle, ReferenceAngle(image, x, y)), 0.01) << x << "," << y;
  }
}

TEST(IntensityCentroidAngle, PointsTowardsTheBrightSide) {
  // Brightness growing along +x gives 0 degrees, along +y (down the image) 90 degrees.
  cv::Mat ramp_x(64, 64, CV_8UC1), ramp_y(64, 64, CV_8UC1);
  for (int r = 0; r < 64; ++r) {
    for (int c = 0; c < 64; ++c) {
      ramp_x.at<uint8_t>(r, c) = static_cast<uint8_t>(2 * c);
      ramp_y.at<uint8_t>(r, c) = static_cast<uint8_t>(2 * r);
    }
  }
  EXPECT_LT(AngleDifference(IntensityCentroidAngle(ramp_x, 32, 32), 0.0), 0.01);
  EXPECT_LT(AngleDifference(IntensityCentroidAngle(ramp_y, 32, 32), 90.0), 0.01);
}

TEST(SteeredBrief, UnrotatedBitsAreThePatternTests) {
  const cv::Mat image = test::TexturedImage(100, 100, 13);
  uint8_t descriptor[kOrbDescriptorBytes];
  SteeredBrief(image, 50, 50, 0.0f, descriptor);
  for (int i = 0; i < 256; ++i) {
    const int8_t* t = kOrbPattern[i];
    const bool expected =
        image.at<uint8_t>(50 + t[1], 50 + t[0]) < image.at<uint8_t>(50 + t[3], 50 + t[2]);
    EXPECT_EQ(((descriptor[i / 8] >> (i % 8)) & 1) != 0, expected) << "bit " << i;
  }
}

TEST(SteeredBrief, FollowsTheImageRotation) {
  // Rotating the image by 90 degrees (clockwise on screen: (x, y) -> (H - 1 - y, x)) and the
  // keypoint angle by +90 degrees must give the same tests, up to rounding ties.
  const cv::Mat image = test::TexturedImage(120, 100, 14);
  cv::Mat rotated;
  cv::rotate(image, rotated, cv::ROTATE_90_CLOCKWISE);
  std::mt19937 rng(15);
  int total_difference = 0;
  for (int i = 0; i < 50; ++i) {
    const int x = 25 + static_cast<int>(rng() % 70);
    const int y = 25 + static_cast<int>(rng() % 50);
    const float angle = static_cast<float>(rng() % 36000) / 100.0f;
    uint8_t a[kOrbDescriptorBytes], b[kOrbDescriptorBytes];
    SteeredBrief(image, x, y, angle, a);
    SteeredBrief(rotated, image.rows - 1 - y, x, std::fmod(angle + 90.0f, 360.0f), b);
    total_difference += Hamming(a, b);
    // Without steering the descriptors of the two views would be unrelated (~128 bits apart).
    uint8_t unsteered[kOrbDescriptorBytes];
    SteeredBrief(rotated, image.rows - 1 - y, x, angle, unsteered);
    EXPECT_GT(Hamming(a, unsteered), 40);
  }
  EXPECT_LE(total_difference, 50);  // at most ~1 bit per descriptor from rounding ties
}

}  // namespace
}  // namespace moslam::feature
