// The Kinect v1 source without a Kinect: every way it cannot open is an InputError naming it.
#include "moslam/sensors/kinect.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/testing/error_of.h"

namespace moslam::sensors {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

TEST(Kinect, IndexIsAWholeNumber) {
  EXPECT_EQ(ParseKinectIndex("0"), 0);
  EXPECT_EQ(ParseKinectIndex("2"), 2);
  EXPECT_THAT(ErrorOf([] { ParseKinectIndex("/dev/video0"); }), HasSubstr("'/dev/video0'"));
  EXPECT_THAT(ErrorOf([] { ParseKinectIndex("-1"); }), HasSubstr("no device index"));
}

TEST(Kinect, AbsentDeviceIsAnErrorNamingIt) {
  // Index 9: no machine that runs these tests has ten Kinects plugged in.
  EXPECT_THAT(ErrorOf([] { OpenKinect(9, {}); }), HasSubstr("kinect:9: "));
}

TEST(Kinect, OnlyItsOwnSize) {
  if (!KinectSupported()) GTEST_SKIP() << "built without libfreenect";
  EXPECT_THAT(ErrorOf([] { OpenKinect(0, cv::Size(1280, 720)); }),
              HasSubstr("kinect:0: gives 640x480 frames, not the 1280x720"));
}

}  // namespace
}  // namespace moslam::sensors
