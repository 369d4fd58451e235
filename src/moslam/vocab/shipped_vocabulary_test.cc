// The vocabulary shipped in data/vocab/ (docs/VOCABULARY.md) loads and describes images.
#include <cmath>

#include <gtest/gtest.h>

#include "moslam/feature/orb_extractor.h"
#include "moslam/feature/test_images.h"
#include "moslam/vocab/database.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::vocab {
namespace {

// Tests run from the source tree (cmake/MoslamHelpers.cmake).
constexpr char kShipped[] = "data/vocab/moslam_orb.mvoc";

TEST(ShippedVocabulary, LoadsWithTheDocumentedShape) {
  const Vocabulary voc = Vocabulary::Load(kShipped);
  EXPECT_EQ(voc.k(), 10);
  EXPECT_EQ(voc.levels(), 5);
  EXPECT_GT(voc.size(), 90000u);
  EXPECT_LE(voc.size(), 100000u);
  // Greedy descent does not always lead a word's own centroid back to it (a centroid may lie
  // nearer to a sibling subtree's centre higher up; DBoW2's trees behave alike), but it should
  // for the great majority of words (96.8 % of the shipped ones, docs/VOCABULARY.md).
  size_t self = 0;
  for (WordId w = 0; w < voc.size(); ++w) {
    EXPECT_GT(voc.Weight(w), 0.0);
    self += voc.Transform(voc.WordDescriptor(w)) == w;
  }
  EXPECT_GT(static_cast<double>(self), 0.9 * static_cast<double>(voc.size()));
}

TEST(ShippedVocabulary, TellsImagesApart) {
  const Vocabulary voc = Vocabulary::Load(kShipped);
  feature::OrbExtractor extractor(feature::OrbExtractorOptions{});
  Database db;
  std::vector<cv::Mat> images;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    images.push_back(feature::test::TexturedImage(640, 480, seed));
    BowVector bow;
    voc.Transform(extractor.Extract(images.back()).descriptors, &bow, nullptr, 1);
    double sum = 0.0;
    for (const auto& [word, value] : bow) sum += value;
    EXPECT_NEAR(sum, 1.0, 1e-9);
    EXPECT_GT(bow.size(), 200u);
    db.Add(seed, bow);
  }
  // A shifted, slightly brighter view of image 3 retrieves image 3.
  cv::Mat view;
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, 12, 0, 1, -9);
  cv::warpAffine(images[2], view, shift, images[2].size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  view += cv::Scalar(10);
  BowVector query;
  voc.Transform(extractor.Extract(view).descriptors, &query, nullptr, 1);
  const std::vector<QueryResult> results = db.Query(query, 5);
  ASSERT_FALSE(results.empty());
  EXPECT_EQ(results[0].id, 3u);
}

}  // namespace
}  // namespace moslam::vocab
