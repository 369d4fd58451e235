// V4L2 cameras: a missing device, a file that is no device and a device that is no camera are
// each an InputError naming it (no camera is needed: none of these opens one).
#include "moslam/io/camera.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::io {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

CameraOptions One(const std::string& device) {
  CameraOptions options;
  options.devices = {device};
  return options;
}

TEST(Camera, IndexNamesItsDevice) {
  EXPECT_EQ(CameraDevicePath("0"), "/dev/video0");
  EXPECT_EQ(CameraDevicePath("12"), "/dev/video12");
  EXPECT_EQ(CameraDevicePath("/dev/video3"), "/dev/video3");
}

TEST(Camera, MissingDeviceIsAnErrorNamingIt) {
  EXPECT_THAT(ErrorOf([] { OpenCamera(One("/dev/video_moslam_absent")); }),
              HasSubstr("/dev/video_moslam_absent: no such camera device"));
  EXPECT_THAT(ErrorOf([] { OpenCamera(One("97")); }), HasSubstr("/dev/video97: no such"));
}

TEST(Camera, FileThatIsNoDeviceIsAnErrorNamingIt) {
  const moslam::testing::TempDir dir;
  const std::string path = dir.Write("video0", "not a device\n");
  EXPECT_THAT(ErrorOf([&] { OpenCamera(One(path)); }),
              HasSubstr(path + ": is not a camera device"));
}

TEST(Camera, DeviceThatIsNoCameraIsAnErrorNamingIt) {
  // A character device that V4L2 does not know.
  EXPECT_THAT(ErrorOf([] { OpenCamera(One("/dev/null")); }),
              HasSubstr("/dev/null: cannot be opened as a V4L2 camera"));
}

TEST(Camera, OptionsAreChecked) {
  CameraOptions none;
  EXPECT_THAT(ErrorOf([&] { none.Check(); }), HasSubstr("one device"));
  CameraOptions pair;
  pair.devices = {"0", "1"};
  pair.side_by_side = true;
  EXPECT_THAT(ErrorOf([&] { pair.Check(); }), HasSubstr("side-by-side stereo takes one device"));
  CameraOptions fps = One("0");
  fps.fps = -1;
  EXPECT_THAT(ErrorOf([&] { fps.Check(); }), HasSubstr("fps"));
}

}  // namespace
}  // namespace moslam::io
