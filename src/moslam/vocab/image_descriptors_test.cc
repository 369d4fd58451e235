#include "moslam/vocab/image_descriptors.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "moslam/feature/orb_extractor.h"
#include "moslam/feature/test_images.h"
#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::vocab {
namespace {

using ::testing::HasSubstr;

TEST(ImageDescriptors, ListsImagesSortedAndExtractsLikeTheExtractor) {
  testing::TempDir dir;
  for (int i : {2, 0, 1}) {
    cv::imwrite(dir.path() + "/" + std::to_string(i) + ".png",
                feature::test::TexturedImage(160, 120, static_cast<uint64_t>(i)));
  }
  dir.Write("notes.txt", "not an image");
  const std::vector<std::string> paths = ListImages(dir.path());
  ASSERT_EQ(paths.size(), 3u);
  EXPECT_THAT(paths[0], HasSubstr("0.png"));
  EXPECT_THAT(paths[2], HasSubstr("2.png"));
  feature::OrbExtractorOptions options;
  options.num_features = 200;
  const std::vector<cv::Mat> one = ExtractDescriptors(paths, options, 1);
  const std::vector<cv::Mat> two = ExtractDescriptors(paths, options, 2);
  ASSERT_EQ(one.size(), 3u);
  feature::OrbExtractor extractor(options);
  for (size_t i = 0; i < 3; ++i) {
    const cv::Mat expected =
        extractor.Extract(cv::imread(paths[i], cv::IMREAD_GRAYSCALE)).descriptors;
    ASSERT_GT(expected.rows, 50);
    EXPECT_EQ(cv::norm(one[i], expected, cv::NORM_HAMMING), 0.0);
    EXPECT_EQ(cv::norm(two[i], expected, cv::NORM_HAMMING), 0.0);
  }
}

TEST(ImageDescriptors, ErrorsNameTheFolderOrFile) {
  testing::TempDir dir;
  EXPECT_THAT(testing::ErrorOf([&] { ListImages(dir.path()); }), HasSubstr(dir.path()));
  const std::string bad = dir.Write("bad.png", "not a png");
  EXPECT_THAT(testing::ErrorOf([&] { ExtractDescriptors({bad}, {}, 1); }), HasSubstr(bad));
}

}  // namespace
}  // namespace moslam::vocab
