#include "moslam/io/image_folder.h"

#include <cmath>
#include <limits>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/io/io_test_util.h"

namespace moslam::io {
namespace {

using test::ErrorOf;
using test::WriteImage;
using ::testing::AllOf;
using ::testing::HasSubstr;

TEST(HasImageExtension, KnownExtensionsAnyCase) {
  for (const char* name : {"a.png", "a.PNG", "b.jpg", "b.JPG", "c.jpeg", "c.JpEg", "d.pgm", "e.ppm",
                           "f.bmp", "dir/g.Bmp"}) {
    EXPECT_TRUE(HasImageExtension(name)) << name;
  }
  for (const char* name : {"a.txt", "a.png.txt", "png", "a.tiff", "a.", "rgb.csv"}) {
    EXPECT_FALSE(HasImageExtension(name)) << name;
  }
}

TEST(ReadImageFolder, SortsByNameAndStampsByRate) {
  testing::TempDir dir;
  WriteImage(dir, "frame_0010.png", 4, 3);
  WriteImage(dir, "frame_0002.JPG", 4, 3);
  WriteImage(dir, "frame_0001.Png", 4, 3);
  WriteImage(dir, "frame_0003.pgm", 4, 3);
  dir.Write("notes.txt", "not an image");
  dir.Write("times.csv", "0,1\n");
  WriteImage(dir, "sub/frame_0000.png", 4, 3);  // subfolders are not read

  const Sequence seq = ReadImageFolder(dir.path(), 20.0);
  EXPECT_EQ(seq.sensor, SensorType::kMonocular);
  ASSERT_EQ(seq.size(), 4u);
  const std::vector<std::string> expected = {"frame_0001.Png", "frame_0002.JPG", "frame_0003.pgm",
                                             "frame_0010.png"};
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(seq.frames[i].image_left, dir.path() + "/" + expected[i]);
    EXPECT_EQ(seq.frames[i].index, static_cast<int>(i));
    EXPECT_DOUBLE_EQ(seq.frames[i].timestamp, i / 20.0);
    EXPECT_TRUE(seq.frames[i].image_right.empty());
  }
  EXPECT_FALSE(seq.ground_truth_path.has_value());
  EXPECT_FALSE(seq.calibration.has_value());
}

TEST(ReadImageFolder, BadInputIsNamed) {
  testing::TempDir dir;
  EXPECT_THAT(ErrorOf([&] { ReadImageFolder(dir.path() + "/none", 10.0); }),
              AllOf(HasSubstr(dir.path() + "/none"), HasSubstr("not found")));
  EXPECT_THAT(ErrorOf([&] { ReadImageFolder(dir.path(), 10.0); }),
              AllOf(HasSubstr(dir.path()), HasSubstr("contains no images")));
  WriteImage(dir, "a.png", 4, 3);
  for (double rate : {0.0, -30.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    EXPECT_THAT(ErrorOf([&] { ReadImageFolder(dir.path(), rate); }),
                AllOf(HasSubstr(dir.path()), HasSubstr("frame rate")))
        << rate;
  }
}

}  // namespace
}  // namespace moslam::io
