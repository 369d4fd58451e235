// Cost of building stereo frames (ORB-SLAM2's Frame constructor for stereo: two extractions plus
// the row-band stereo matching) on KITTI 06 frames 0-9 (1226x370 grey, 2000 features per image),
// and of the stereo matching step alone. Without the shared data a synthetic textured image and
// its 12.4-pixel shifted copy stand in. OpenCV runs single-threaded, as in orb_benchmark.cc, and
// the two images are extracted one after the other (ORB-SLAM2 uses two threads).
//
//   build/src/moslam/feature/bench_feature_frame --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true   (one command line)
#include <optional>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/feature/frame.h"
#include "moslam/feature/test_images.h"
#include "moslam/io/image.h"
#include "moslam/io/kitti.h"
#include "moslam/testing/shared_data.h"

namespace moslam::feature {
namespace {

constexpr int kPairs = 10;

const bool kSingleThreaded = [] {
  cv::setNumThreads(0);
  return true;
}();

struct StereoSet {
  std::vector<cv::Mat> left, right;
  std::optional<camera::StereoCamera> camera;
  bool real = false;
};

StereoSet LoadSet() {
  StereoSet set;
  const std::string dir = testing::FindShared("data/kitti/06_000000-000050");
  if (!dir.empty()) {
    const io::Sequence seq = io::ReadKitti(dir);
    for (int i = 0; i < kPairs && i < static_cast<int>(seq.size()); ++i) {
      io::FrameImages images = io::LoadFrameImages(seq.frames[i], io::ColourMode::kGrey);
      set.left.push_back(images.left);
      set.right.push_back(images.right);
    }
    set.camera.emplace(seq.calibration->camera, seq.calibration->bf);
    set.real = true;
    return set;
  }
  camera::PinholeOptions o;
  o.fx = o.fy = 707.1;
  o.cx = 601.9;
  o.cy = 183.1;
  o.width = 1226;
  o.height = 370;
  set.camera.emplace(o, 379.8);
  for (int i = 0; i < kPairs; ++i) {
    const cv::Mat left = test::TexturedImage(1226, 370, i);
    const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, -12.4, 0, 1, 0);
    cv::Mat right;
    cv::warpAffine(left, right, shift, left.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
    set.left.push_back(left);
    set.right.push_back(right);
  }
  return set;
}

const StereoSet& Set() {
  static const StereoSet set = LoadSet();
  return set;
}

OrbExtractorOptions Options() {
  OrbExtractorOptions o;
  o.num_features = 2000;
  return o;
}

void BM_StereoFrame(benchmark::State& state) {
  const StereoSet& set = Set();
  OrbExtractor left(Options()), right(Options());
  size_t i = 0;
  double with_depth = 0, keypoints = 0;
  for (auto _ : state) {
    const size_t k = i++ % set.left.size();
    const Frame frame = MakeStereoFrame(static_cast<double>(k), set.left[k], set.right[k],
                                        cv::Mat(), &left, &right, *set.camera);
    with_depth += frame.NumWithDepth();
    keypoints += static_cast<double>(frame.size());
  }
  state.counters["keypoints"] = keypoints / static_cast<double>(state.iterations());
  state.counters["stereo_matches"] = with_depth / static_cast<double>(state.iterations());
  state.SetLabel(set.real ? "kitti06 1226x370" : "synthetic 1226x370");
}
BENCHMARK(BM_StereoFrame)->Unit(benchmark::kMillisecond);

// The matching step alone, on extractions made outside the timed loop.
void BM_StereoMatchOnly(benchmark::State& state) {
  const StereoSet& set = Set();
  OrbExtractor left(Options()), right(Options());
  const OrbFeatures lf = left.Extract(set.left[0]);
  const OrbFeatures rf = right.Extract(set.right[0]);
  double matches = 0;
  for (auto _ : state) {
    const StereoMatches m =
        MatchStereo(lf, left, rf, right, set.camera->bf(), set.camera->left().fx());
    matches += m.num_matches;
  }
  state.counters["stereo_matches"] = matches / static_cast<double>(state.iterations());
  state.SetLabel(set.real ? "kitti06 frame 0" : "synthetic");
}
BENCHMARK(BM_StereoMatchOnly)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace moslam::feature
