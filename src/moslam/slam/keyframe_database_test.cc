// The keyframe database's queries on hand-made BoW vectors and covisibility, where every score is
// known: 20 words of weight 1/20 per image, so sharing s words scores s / 20 (L1 scoring).
#include "moslam/slam/keyframe_database.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "moslam/slam/test_scene.h"
#include "moslam/vocab/test_descriptors.h"

namespace moslam::slam {
namespace {

using testing::CameraAt;
using testing::ObserveScene;
using testing::RandomScene;

std::shared_ptr<const vocab::Vocabulary> TinyVocabulary() {
  // The queries only use Vocabulary::Score; the database needs a non-empty vocabulary.
  cv::RNG rng(1);
  std::vector<cv::Mat> images = {vocab::test::RandomDescriptors(40, rng),
                                 vocab::test::RandomDescriptors(40, rng)};
  vocab::VocabularyTrainOptions options;
  options.k = 4;
  options.levels = 2;
  return std::make_shared<const vocab::Vocabulary>(vocab::Vocabulary::Train(images, options));
}

// `shared` words from 0.., the rest of the 20 from `own`...
vocab::BowVector Bow(int shared, uint32_t own) {
  vocab::BowVector bow;
  for (int w = 0; w < shared; ++w) bow[w] = 0.05;
  for (int w = shared; w < 20; ++w) bow[own + w] = 0.05;
  return bow;
}

void Connect(const std::shared_ptr<map::KeyFrame>& a, const std::shared_ptr<map::KeyFrame>& b,
             int weight) {
  a->AddConnection(b, weight);
  b->AddConnection(a, weight);
}

struct Fixture {
  map::Map map;
  KeyFrameDatabase db{TinyVocabulary()};
  testing::Scene scene = RandomScene(10, 1);
  vocab::BowVector query = Bow(20, 0);  // words 0..19
  std::shared_ptr<map::KeyFrame> root, a0, a1, a2, a3, b0, b1, c;

  std::shared_ptr<map::KeyFrame> Add(int shared, uint32_t own) {
    auto kf = ObserveScene(&map, scene, CameraAt(0.1 * map.next_keyframe_id()));
    kf->bow = Bow(shared, own);
    if (root) kf->SetParent(root);
    db.Add(kf);
    return kf;
  }
  Fixture() {
    root = Add(0, 900);  // shares nothing; the map's first keyframe (never erased)
    a0 = Add(5, 100);    // 5 shared words: under 0.8 x 16, not scored
    a1 = Add(16, 200);   // score 0.80
    a2 = Add(14, 300);   // score 0.70
    a3 = Add(0, 400);
    b0 = Add(13, 500);  // score 0.65
    b1 = Add(13, 600);  // score 0.65
    c = Add(0, 700);
    Connect(a0, a1, 40);
    Connect(a1, a2, 30);
    Connect(a2, a3, 20);
    Connect(b0, b1, 30);
  }
};

TEST(KeyFrameDatabase, RelocalizationCandidatesAccumulateOverCovisibles) {
  Fixture fx;
  EXPECT_EQ(fx.db.size(), 8u);
  // Groups: a1 + a2 = 1.5 (best a1), b0 + b1 = 1.3 (> 0.75 x 1.5), returned as each group's best.
  const auto candidates = fx.db.DetectRelocalizationCandidates(fx.query);
  ASSERT_EQ(candidates.size(), 3u);
  EXPECT_EQ(candidates[0], fx.a1);
  EXPECT_EQ(candidates[1], fx.b0);
  EXPECT_EQ(candidates[2], fx.b1);
  // Without b1's support b0 alone (0.65) falls under 0.75 x 1.5.
  fx.db.Erase(*fx.b1);
  EXPECT_EQ(fx.db.DetectRelocalizationCandidates(fx.query),
            std::vector<std::shared_ptr<map::KeyFrame>>{fx.a1});
  EXPECT_TRUE(fx.db.DetectRelocalizationCandidates(vocab::BowVector{{999, 1.0}}).empty());
}

TEST(KeyFrameDatabase, LoopCandidatesExcludeConnectedAndApplyMinScore) {
  Fixture fx;
  // A new keyframe that sees words 0..19, connected to a2.
  auto k = fx.Add(20, 0);
  Connect(k, fx.a2, 50);
  // Scored (not k, not a2): a1 0.80, b0 0.65, b1 0.65 (a0 under the shared-words cut).
  // min score 0.68: only a1 starts a group -> a1.
  EXPECT_EQ(fx.db.DetectLoopCandidates(*k, 0.68),
            std::vector<std::shared_ptr<map::KeyFrame>>{fx.a1});
  // min score 0.6: b0 + b1 = 1.3 beats a1 alone (0.8 < 0.75 x 1.3).
  const auto loops = fx.db.DetectLoopCandidates(*k, 0.6);
  ASSERT_EQ(loops.size(), 2u);
  EXPECT_EQ(loops[0], fx.b0);
  EXPECT_EQ(loops[1], fx.b1);
  // ORB-SLAM2's min score: the lowest score of k with its covisibles (a2: 0.70).
  EXPECT_NEAR(fx.db.MinCovisibleScore(*k), 0.70, 1e-9);
  EXPECT_DOUBLE_EQ(fx.db.MinCovisibleScore(*fx.c), 1.0);  // no covisibles
}

TEST(RecentWordWeights, LocalInverseDocumentFrequency) {
  const RecentWordWeights identity;
  EXPECT_EQ(identity.keyframes(), 0);
  EXPECT_DOUBLE_EQ(identity.Factor(3), 1.0);
  const vocab::BowVector bow = {{1, 0.25}, {2, 0.25}, {3, 0.5}};
  EXPECT_EQ(identity.Apply(bow), bow);
  // 4 recent keyframes: word 1 in all of them, word 2 in one, word 3 in none.
  const RecentWordWeights w({{1, 4}, {2, 1}}, 4);
  EXPECT_DOUBLE_EQ(w.Factor(1), 0.0);
  EXPECT_NEAR(w.Factor(2), std::log(2.5) / std::log(5.0), 1e-12);
  EXPECT_DOUBLE_EQ(w.Factor(3), 1.0);
  const vocab::BowVector out = w.Apply(bow);
  ASSERT_EQ(out.size(), 2u);  // word 1 has weight 0: gone
  const double v2 = 0.25 * w.Factor(2);
  EXPECT_NEAR(out.at(2), v2 / (v2 + 0.5), 1e-12);
  EXPECT_NEAR(out.at(3), 0.5 / (v2 + 0.5), 1e-12);
  EXPECT_TRUE(w.Apply(vocab::BowVector{{1, 1.0}}).empty());
}

// A street of identical houses: the alias shares more words with the new keyframe than the true
// place does, but those words are the ones every recently passed place holds as well.
TEST(KeyFrameDatabase, RecentlyRepeatedWordsDoNotMakeALoop) {
  map::Map map;
  KeyFrameDatabase db(TinyVocabulary());
  const testing::Scene scene = RandomScene(10, 1);
  const auto add = [&](std::vector<vocab::WordId> words) {
    auto kf = ObserveScene(&map, scene, CameraAt(0.1 * map.next_keyframe_id()));
    for (const vocab::WordId w : words) kf->bow[w] = 1.0 / static_cast<double>(words.size());
    db.Add(kf);
    return kf;
  };
  const auto range = [](vocab::WordId from, vocab::WordId to, std::vector<vocab::WordId> v) {
    for (vocab::WordId w = from; w < to; ++w) v.push_back(w);
    return v;
  };
  add(range(900, 920, {}));                                   // the first keyframe: nothing shared
  const auto alias = add(range(100, 107, range(0, 13, {})));  // words 0..12 of the query
  const auto place = add(range(200, 209, range(9, 20, {})));  // words 9..19
  std::vector<std::shared_ptr<map::KeyFrame>> recent;
  for (int i = 0; i < 6; ++i) {  // houses passed since: words 0..8 (the facade) and their own
    recent.push_back(add(range(300 + 20 * i, 311 + 20 * i, range(0, 9, {}))));
  }
  const auto k = add(range(0, 20, {}));

  // ORB-SLAM2's scores: alias 0.65, place 0.55 (> 0.75 x 0.65): both, the alias first.
  EXPECT_EQ(db.DetectLoopCandidates(*k, 0.0),
            (std::vector<std::shared_ptr<map::KeyFrame>>{alias, place}));

  // The six houses passed since hold words 0..8: weight 0, the place alone remains.
  const RecentWordWeights w = db.RecentPastWeights(*k, 6, 5);
  EXPECT_EQ(w.keyframes(), 6);
  EXPECT_DOUBLE_EQ(w.Factor(0), 0.0);
  EXPECT_DOUBLE_EQ(w.Factor(9), 1.0);
  EXPECT_EQ(db.DetectLoopCandidates(*k, 0.0, w),
            std::vector<std::shared_ptr<map::KeyFrame>>{place});

  // Keyframes in view of k are not its past: connected to the last house, the six are the
  // other five and the place (which holds none of words 0..8).
  Connect(k, recent.back(), 30);
  const RecentWordWeights w2 = db.RecentPastWeights(*k, 6, 5);
  EXPECT_EQ(w2.keyframes(), 6);
  EXPECT_NEAR(w2.Factor(0), std::log(7.0 / 6.0) / std::log(7.0), 1e-12);
  // Too few predecessors for counts to mean anything: the identity.
  EXPECT_EQ(db.RecentPastWeights(*k, 20, 10).keyframes(), 0);
}

TEST(KeyFrameDatabase, ErasedThroughTheMapListener) {
  Fixture fx;
  fx.map.SetKeyFrameEraseListener([&](const map::KeyFrame& kf) { fx.db.Erase(kf); });
  fx.map.EraseKeyFrame(fx.a1);
  EXPECT_FALSE(fx.db.Contains(fx.a1->id));
  EXPECT_EQ(fx.db.size(), 7u);
  for (const auto& kf : fx.db.DetectRelocalizationCandidates(fx.query)) EXPECT_NE(kf, fx.a1);
  fx.db.Add(fx.a2);  // twice: no-op
  EXPECT_EQ(fx.db.size(), 7u);
}

TEST(KeyFrameDatabase, ComputeBowUsesTheOrbSlam2DirectIndexLevel) {
  const auto voc = TinyVocabulary();
  EXPECT_EQ(DirectIndexLevel(*voc), 0);  // 2 levels: the root's children
  KeyFrameDatabase db(voc);
  cv::RNG rng(5);
  const cv::Mat d = vocab::test::RandomDescriptors(30, rng);
  const KeyFrameBow b = db.ComputeBow(d);
  vocab::BowVector bow;
  vocab::FeatureVector fv;
  voc->Transform(d, &bow, &fv, 0);
  EXPECT_EQ(b.bow, bow);
  EXPECT_EQ(b.features, fv);
  EXPECT_TRUE(db.ComputeBow(cv::Mat()).bow.empty());
}

}  // namespace
}  // namespace moslam::slam
