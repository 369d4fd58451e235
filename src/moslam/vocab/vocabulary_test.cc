#include "moslam/vocab/vocabulary.h"

#include <cmath>
#include <set>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"
#include "moslam/vocab/test_descriptors.h"

namespace moslam::vocab {
namespace {

using ::testing::HasSubstr;

// 8 prototypes x 8 sub-prototypes (40 bits apart) x 30 samples (6 bits from theirs), in 24
// training images.
std::vector<cv::Mat> ClusteredImages(uint64_t seed) {
  cv::RNG rng(seed);
  return test::SplitRows(test::ClusteredDescriptors(8, 8, 30, 40, 6, rng), 24);
}

VocabularyTrainOptions SmallOptions(int k, int levels) {
  VocabularyTrainOptions options;
  options.k = k;
  options.levels = levels;
  return options;
}

TEST(Vocabulary, EveryWordsCentroidMapsToThatWord) {
  const Vocabulary voc = Vocabulary::Train(ClusteredImages(1), SmallOptions(8, 2));
  ASSERT_GT(voc.size(), 8u);
  EXPECT_LE(voc.size(), 64u);
  for (WordId w = 0; w < voc.size(); ++w) {
    EXPECT_EQ(voc.Transform(voc.WordDescriptor(w)), w) << "word " << w;
  }
}

TEST(Vocabulary, AFewFlippedBitsKeepTheWordOnClusteredData) {
  const Vocabulary voc = Vocabulary::Train(ClusteredImages(2), SmallOptions(8, 2));
  cv::RNG rng(7);
  for (WordId w = 0; w < voc.size(); ++w) {
    uint8_t d[32];
    std::memcpy(d, voc.WordDescriptor(w), 32);
    test::FlipBits(d, 3, rng);
    EXPECT_EQ(voc.Transform(d), w) << "word " << w;
  }
}

TEST(Vocabulary, TreeHasAtMostKChildrenPerNodeAndLevelsDepth) {
  cv::RNG rng(3);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 10; ++i) images.push_back(test::RandomDescriptors(100, rng));
  const Vocabulary voc = Vocabulary::Train(images, SmallOptions(5, 3));
  EXPECT_EQ(voc.k(), 5);
  EXPECT_EQ(voc.levels(), 3);
  // 1000 distinct random descriptors fill nearly all 125 leaves of a 5 x 5 x 5 tree.
  EXPECT_GT(voc.size(), 100u);
  EXPECT_LE(voc.size(), 125u);
  std::set<NodeId> top, middle;
  for (WordId w = 0; w < voc.size(); ++w) {
    const NodeId node = voc.WordNode(w);
    EXPECT_EQ(voc.AncestorAtLevel(node, 2), node) << "word " << w << " deeper than 3 levels";
    top.insert(voc.AncestorAtLevel(node, 0));
    middle.insert(voc.AncestorAtLevel(node, 1));
  }
  EXPECT_EQ(top.size(), 5u);
  EXPECT_LE(middle.size(), 25u);
}

TEST(Vocabulary, TrainingIsDeterministicForASeedWhateverTheThreads) {
  const std::vector<cv::Mat> images = ClusteredImages(4);
  VocabularyTrainOptions options = SmallOptions(6, 3);
  options.seed = 42;
  const Vocabulary a = Vocabulary::Train(images, options);
  options.num_threads = 3;
  const Vocabulary b = Vocabulary::Train(images, options);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.num_nodes(), b.num_nodes());
  for (WordId w = 0; w < a.size(); ++w) {
    EXPECT_EQ(std::memcmp(a.WordDescriptor(w), b.WordDescriptor(w), 32), 0);
    EXPECT_EQ(a.Weight(w), b.Weight(w));
    EXPECT_EQ(a.WordNode(w), b.WordNode(w));
  }
}

TEST(Vocabulary, WeightsAreInverseDocumentFrequencies) {
  cv::RNG rng(5);
  const cv::Mat all = test::ClusteredDescriptors(6, 6, 20, 40, 6, rng);
  // Rows shuffled into 30 images, so that words appear in different numbers of images.
  std::vector<cv::Mat> images(30);
  for (int r = 0; r < all.rows; ++r) images[rng.uniform(0, 30)].push_back(all.row(r));
  const Vocabulary voc = Vocabulary::Train(images, SmallOptions(6, 2));
  std::vector<std::set<int>> images_of_word(voc.size());
  for (int i = 0; i < 30; ++i) {
    for (int r = 0; r < images[i].rows; ++r) {
      images_of_word[voc.Transform(images[i].ptr<uint8_t>(r))].insert(i);
    }
  }
  for (WordId w = 0; w < voc.size(); ++w) {
    const double n = std::max<size_t>(images_of_word[w].size(), 1);
    EXPECT_NEAR(voc.Weight(w), std::log(30.0 / n), 1e-12) << "word " << w;
  }
}

TEST(Vocabulary, BowVectorsAreNormalizedAndScoredByL1) {
  cv::RNG rng(6);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 20; ++i) images.push_back(test::RandomDescriptors(200, rng));
  const Vocabulary voc = Vocabulary::Train(images, SmallOptions(8, 3));
  BowVector a, b;
  voc.Transform(images[0], &a, nullptr, 0);
  voc.Transform(images[1], &b, nullptr, 0);
  double sum = 0.0;
  for (const auto& [w, v] : a) {
    EXPECT_GT(v, 0.0);
    sum += v;
  }
  EXPECT_NEAR(sum, 1.0, 1e-12);
  EXPECT_NEAR(Vocabulary::Score(a, a), 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(Vocabulary::Score(a, b), Vocabulary::Score(b, a));
  // Against the definition: 1 - |a - b|_1 / 2 over the union of words.
  std::map<WordId, double> diff;
  for (const auto& [w, v] : a) diff[w] += v;
  for (const auto& [w, v] : b) diff[w] -= v;
  double l1 = 0.0;
  for (const auto& [w, v] : diff) l1 += std::abs(v);
  EXPECT_NEAR(Vocabulary::Score(a, b), 1.0 - 0.5 * l1, 1e-12);
  EXPECT_EQ(Vocabulary::Score(a, BowVector{}), 0.0);
  BowVector disjoint{{static_cast<WordId>(voc.size()) + 5, 1.0}};
  EXPECT_EQ(Vocabulary::Score(a, disjoint), 0.0);
}

TEST(Vocabulary, ScoringRanksTheSameImageFirst) {
  // 20 images of 300 random descriptors; each query is a noisy copy (12 of 256 bits flipped in
  // every descriptor, a third of them replaced by unrelated descriptors).
  cv::RNG rng(8);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 20; ++i) images.push_back(test::RandomDescriptors(300, rng));
  const Vocabulary voc = Vocabulary::Train(images, SmallOptions(8, 3));
  std::vector<BowVector> bows(images.size());
  for (size_t i = 0; i < images.size(); ++i) voc.Transform(images[i], &bows[i], nullptr, 1);
  for (size_t q = 0; q < images.size(); ++q) {
    BowVector query;
    voc.Transform(test::NoisyCopy(images[q], 12, 100, rng), &query, nullptr, 1);
    size_t best = 0;
    for (size_t i = 1; i < images.size(); ++i) {
      if (Vocabulary::Score(query, bows[i]) > Vocabulary::Score(query, bows[best])) best = i;
    }
    EXPECT_EQ(best, q);
  }
}

TEST(Vocabulary, DirectIndexGroupsFeaturesByTheirAncestorAtTheLevel) {
  const std::vector<cv::Mat> images = ClusteredImages(9);
  const Vocabulary voc = Vocabulary::Train(images, SmallOptions(8, 2));
  for (int level = 0; level < 2; ++level) {
    BowVector bow;
    FeatureVector fv;
    voc.Transform(images[3], &bow, &fv, level);
    std::set<uint32_t> seen;
    for (const auto& [node, features] : fv) {
      for (uint32_t f : features) {
        EXPECT_TRUE(seen.insert(f).second) << "feature " << f << " listed twice";
        const WordId w = voc.Transform(images[3].ptr<uint8_t>(static_cast<int>(f)));
        EXPECT_EQ(voc.AncestorAtLevel(voc.WordNode(w), level), node);
        EXPECT_GT(voc.Weight(w), 0.0);
      }
    }
    size_t positive = 0;
    for (int r = 0; r < images[3].rows; ++r)
      positive += voc.Weight(voc.Transform(images[3].ptr<uint8_t>(r))) > 0.0;
    EXPECT_EQ(seen.size(), positive);
  }
  EXPECT_EQ(voc.DirectIndexLevelFromLeaves(1), 0);
  EXPECT_EQ(voc.DirectIndexLevelFromLeaves(4), 0);
}

TEST(Vocabulary, ProgressReachesOne) {
  double last = -1.0;
  bool monotonic = true;
  Vocabulary::Train(ClusteredImages(10), SmallOptions(4, 3), [&](double f) {
    monotonic = monotonic && f >= last && f <= 1.0;
    last = f;
  });
  EXPECT_TRUE(monotonic);
  EXPECT_EQ(last, 1.0);
}

TEST(Vocabulary, BadOptionsAndInputsAreNamed) {
  VocabularyTrainOptions options;
  options.k = 1;
  EXPECT_THAT(testing::ErrorOf([&] { options.Check(); }), HasSubstr("k must be"));
  options = VocabularyTrainOptions();
  options.levels = 0;
  EXPECT_THAT(testing::ErrorOf([&] { options.Check(); }), HasSubstr("levels"));
  options = VocabularyTrainOptions();
  options.num_threads = 0;
  EXPECT_THAT(testing::ErrorOf([&] { options.Check(); }), HasSubstr("num_threads"));
  EXPECT_THAT(testing::ErrorOf([] { Vocabulary::Train({}, VocabularyTrainOptions()); }),
              HasSubstr("at least one descriptor"));
  const std::vector<cv::Mat> wrong{cv::Mat(4, 16, CV_8UC1, cv::Scalar(0))};
  EXPECT_THAT(testing::ErrorOf([&] { Vocabulary::Train(wrong, VocabularyTrainOptions()); }),
              HasSubstr("training image 0"));
}

}  // namespace
}  // namespace moslam::vocab
