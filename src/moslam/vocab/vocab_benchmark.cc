// Speed of the vocabulary: loading the shipped file, transforming an image's descriptors, scoring
// two images and querying a database.
//
// The shipped vocabulary is data/vocab/moslam_orb.mvoc (docs/VOCABULARY.md); without it a small
// vocabulary (k = 10, L = 4, trained here on random descriptors) stands in and the benchmark
// names say so. Descriptors are random: a descent costs the same k distances per level whatever
// the bits, so the Transform time does not depend on the images.
//
//   build/src/moslam/vocab/bench_vocab --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true   (one command line)
#include <filesystem>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "moslam/vocab/database.h"
#include "moslam/vocab/test_descriptors.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::vocab {
namespace {

const std::string kShipped = std::string(MOSLAM_SOURCE_DIR) + "/data/vocab/moslam_orb.mvoc";

// The file the benchmarks load: the shipped vocabulary, or a stand-in written once.
const std::string& VocabularyPath() {
  static const std::string path = [] {
    if (std::filesystem::exists(kShipped)) return kShipped;
    cv::RNG rng(1);
    std::vector<cv::Mat> images;
    for (int i = 0; i < 100; ++i) images.push_back(test::RandomDescriptors(500, rng));
    VocabularyTrainOptions options;
    options.k = 10;
    options.levels = 4;
    const std::string stand_in =
        (std::filesystem::temp_directory_path() / "bench_vocab_stand_in.mvoc").string();
    Vocabulary::Train(images, options).Save(stand_in);
    return stand_in;
  }();
  return path;
}

const Vocabulary& Loaded() {
  static const Vocabulary voc = Vocabulary::Load(VocabularyPath());
  return voc;
}

void BM_Load(benchmark::State& state) {
  for (auto _ : state) {
    Vocabulary voc = Vocabulary::Load(VocabularyPath());
    benchmark::DoNotOptimize(voc.size());
  }
  state.SetLabel(VocabularyPath() == kShipped ? "shipped" : "stand-in (no shipped file)");
  state.counters["words"] = static_cast<double>(Loaded().size());
}
BENCHMARK(BM_Load)->Unit(benchmark::kMillisecond);

// One image: 1000 descriptors -> BoW vector and direct index (ORB-SLAM2's per-keyframe cost).
void BM_Transform1000(benchmark::State& state) {
  const Vocabulary& voc = Loaded();
  cv::RNG rng(2);
  const cv::Mat descriptors = test::RandomDescriptors(1000, rng);
  const int level = voc.DirectIndexLevelFromLeaves(4);
  BowVector bow;
  FeatureVector fv;
  for (auto _ : state) {
    voc.Transform(descriptors, &bow, &fv, level);
    benchmark::DoNotOptimize(bow.size());
  }
  state.SetItemsProcessed(state.iterations() * descriptors.rows);
}
BENCHMARK(BM_Transform1000)->Unit(benchmark::kMicrosecond);

void BM_Score(benchmark::State& state) {
  const Vocabulary& voc = Loaded();
  cv::RNG rng(3);
  BowVector a, b;
  voc.Transform(test::RandomDescriptors(1000, rng), &a, nullptr, 0);
  voc.Transform(test::RandomDescriptors(1000, rng), &b, nullptr, 0);
  for (auto _ : state) benchmark::DoNotOptimize(Vocabulary::Score(a, b));
}
BENCHMARK(BM_Score)->Unit(benchmark::kMicrosecond);

// A query against `range(0)` entries of 1000 random descriptors each.
void BM_DatabaseQuery(benchmark::State& state) {
  const Vocabulary& voc = Loaded();
  cv::RNG rng(4);
  Database db;
  for (int i = 0; i < state.range(0); ++i) {
    BowVector bow;
    voc.Transform(test::RandomDescriptors(1000, rng), &bow, nullptr, 0);
    db.Add(static_cast<uint64_t>(i), bow);
  }
  BowVector query;
  voc.Transform(test::RandomDescriptors(1000, rng), &query, nullptr, 0);
  for (auto _ : state) benchmark::DoNotOptimize(db.Query(query, 10, 0.8));
}
BENCHMARK(BM_DatabaseQuery)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace moslam::vocab
