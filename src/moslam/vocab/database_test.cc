#include "moslam/vocab/database.h"

#include <gtest/gtest.h>

#include "moslam/vocab/test_descriptors.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::vocab {
namespace {

TEST(Database, QueryReturnsTheNoisyCopysImageFirst) {
  cv::RNG rng(11);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 20; ++i) images.push_back(test::RandomDescriptors(300, rng));
  VocabularyTrainOptions options;
  options.k = 8;
  options.levels = 3;
  const Vocabulary voc = Vocabulary::Train(images, options);
  Database db;
  for (size_t i = 0; i < images.size(); ++i) {
    BowVector bow;
    voc.Transform(images[i], &bow, nullptr, 0);
    db.Add(1000 + i, bow);
  }
  EXPECT_EQ(db.size(), 20u);
  for (size_t q = 0; q < images.size(); ++q) {
    BowVector query;
    voc.Transform(test::NoisyCopy(images[q], 12, 100, rng), &query, nullptr, 0);
    const std::vector<QueryResult> results = db.Query(query, 5, 0.0);
    ASSERT_EQ(results.size(), 5u);
    EXPECT_EQ(results[0].id, 1000 + q);
    EXPECT_NEAR(results[0].score, Vocabulary::Score(query, *db.Find(1000 + q)), 1e-15);
    for (size_t i = 1; i < results.size(); ++i) EXPECT_GE(results[i - 1].score, results[i].score);
  }
}

TEST(Database, SharingWordsCountsCommonWords) {
  Database db;
  db.Add(1, {{1, 0.5}, {2, 0.5}});
  db.Add(2, {{2, 0.25}, {3, 0.75}});
  db.Add(3, {{9, 1.0}});
  const auto sharing = db.SharingWords({{1, 0.2}, {2, 0.3}, {3, 0.5}});
  ASSERT_EQ(sharing.size(), 2u);
  EXPECT_EQ(sharing[0], std::make_pair(uint64_t{1}, 2));
  EXPECT_EQ(sharing[1], std::make_pair(uint64_t{2}, 2));
}

TEST(Database, EraseRemovesEveryPosting) {
  Database db;
  const BowVector a{{1, 0.5}, {2, 0.5}};
  const BowVector b{{1, 0.5}, {3, 0.5}};
  db.Add(7, a);
  db.Add(8, b);
  db.Erase(7, a);
  EXPECT_EQ(db.size(), 1u);
  EXPECT_EQ(db.Find(7), nullptr);
  ASSERT_NE(db.Find(8), nullptr);
  const std::vector<QueryResult> results = db.Query(a, -1);
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(results[0].id, 8u);
  EXPECT_EQ(results[0].shared_words, 1);
  EXPECT_TRUE(db.SharingWords({{2, 1.0}}).empty());
  db.Erase(7, a);  // unknown id: nothing happens
  db.Erase(8, b);
  EXPECT_EQ(db.size(), 0u);
  EXPECT_TRUE(db.Query(a, 10).empty());
}

TEST(Database, AddingAnIdAgainReplacesIt) {
  Database db;
  db.Add(1, {{1, 1.0}});
  db.Add(1, {{2, 1.0}});
  EXPECT_EQ(db.size(), 1u);
  EXPECT_TRUE(db.SharingWords({{1, 1.0}}).empty());
  EXPECT_EQ(db.SharingWords({{2, 1.0}}).size(), 1u);
}

TEST(Database, MinSharedFractionAndMaxResultsFilter) {
  Database db;
  db.Add(1, {{1, 0.25}, {2, 0.25}, {3, 0.25}, {4, 0.25}});
  db.Add(2, {{1, 0.5}, {2, 0.5}});
  db.Add(3, {{1, 1.0}});
  db.Add(4, {{1, 1.0}});  // ties with 3: lower id first
  const BowVector query{{1, 0.25}, {2, 0.25}, {3, 0.25}, {4, 0.25}};
  const std::vector<QueryResult> all = db.Query(query, -1, 0.0);
  ASSERT_EQ(all.size(), 4u);
  EXPECT_EQ(all[0].id, 1u);
  EXPECT_DOUBLE_EQ(all[0].score, 1.0);
  EXPECT_EQ(all[0].shared_words, 4);
  EXPECT_EQ(all[1].id, 2u);
  EXPECT_DOUBLE_EQ(all[1].score, 0.5);
  EXPECT_EQ(all[2].id, 3u);
  EXPECT_EQ(all[3].id, 4u);
  // 0.5 of the best's 4 shared words: entries with at least 2.
  const std::vector<QueryResult> half = db.Query(query, -1, 0.5);
  ASSERT_EQ(half.size(), 2u);
  EXPECT_EQ(db.Query(query, 1, 0.0).size(), 1u);
  db.Clear();
  EXPECT_EQ(db.size(), 0u);
  EXPECT_TRUE(db.Query(query, -1).empty());
}

}  // namespace
}  // namespace moslam::vocab
