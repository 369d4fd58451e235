// Speed of the ORB extractor against OpenCV's cv::ORB (same budget, scale factor, levels and FAST
// threshold 20) and the cost of the movable-object mask.
//
// Images: KITTI 06 frames 0-9 of image_0 (1226x370 grey) with 2000 features, and CamVid val
// images 0-9 (480x360 colour -> grey, upscaled to 640x480 with bilinear interpolation) with 1000
// features. Without the shared data, synthetic textured images of the same sizes stand in.
// Masks: rectangles and ellipses covering ~30% of each image. Each iteration processes the next
// image of the set, so all variants see the same images. OpenCV runs single-threaded here
// (cv::setNumThreads(0)): both extractors are then entirely on the benchmark thread, so that CPU
// time counts all their work and stays comparable on a loaded machine.
//
//   build/src/moslam/feature/bench_feature --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true   (one command line)
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/feature/orb_extractor.h"
#include "moslam/feature/test_images.h"
#include "moslam/testing/shared_data.h"

namespace moslam::feature {
namespace {

constexpr int kImagesPerSet = 10;

// Runs before main (before any benchmark).
const bool kSingleThreaded = [] {
  cv::setNumThreads(0);
  return true;
}();

struct ImageSet {
  std::vector<cv::Mat> images;
  std::vector<cv::Mat> masks;
  int features = 0;
  bool real = false;
};

ImageSet LoadSet(bool kitti) {
  ImageSet set;
  set.features = kitti ? 2000 : 1000;
  std::vector<cv::String> paths;
  const std::string dir =
      testing::FindShared(kitti ? "data/kitti/06_000000-000050/image_0" : "data/camvid/val");
  if (!dir.empty()) cv::glob(dir + (kitti ? "/*.png" : "/*.jpg"), paths, false);
  for (int i = 0; i < kImagesPerSet; ++i) {
    cv::Mat image;
    if (i < static_cast<int>(paths.size())) {
      image = cv::imread(paths[i], cv::IMREAD_GRAYSCALE);
      if (!kitti) cv::resize(image, image, cv::Size(640, 480), 0, 0, cv::INTER_LINEAR);
    }
    set.real = set.real || !image.empty();
    if (image.empty()) {
      image = kitti ? test::TexturedImage(1226, 370, i) : test::TexturedImage(640, 480, i);
    }
    set.images.push_back(image);
    set.masks.push_back(test::MovableMask(image.size(), 0.3, 100 + i));
  }
  return set;
}

const ImageSet& Set(bool kitti) {
  static const ImageSet kitti_set = LoadSet(true);
  static const ImageSet vga_set = LoadSet(false);
  return kitti ? kitti_set : vga_set;
}

void Label(benchmark::State& state, const ImageSet& set, bool kitti) {
  const cv::Size size = set.images[0].size();
  state.SetLabel(std::string(kitti ? "kitti06 " : "camvid->vga ") + std::to_string(size.width) +
                 "x" + std::to_string(size.height) + (set.real ? "" : " (synthetic)"));
}

// Arguments: 0 = KITTI set, 1 = 640x480 set; mask: 0 none, 1 the ~30% mask, 2 the same mask
// grown by 5 pixels (mask_dilation_px), 3 the ~30% mask while a viewer watches (the keypoints it
// took away found too: set_keep_masked).
void BM_MoslamOrb(benchmark::State& state) {
  const bool kitti = state.range(0) == 0;
  const bool masked = state.range(1) != 0;
  const ImageSet& set = Set(kitti);
  OrbExtractorOptions options;
  options.num_features = set.features;
  options.mask_dilation_px = state.range(1) == 2 ? 5 : 0;
  OrbExtractor extractor(options);
  extractor.set_keep_masked(state.range(1) == 3);
  OrbFeatures features;
  size_t i = 0;
  double keypoints = 0;
  for (auto _ : state) {
    const size_t k = i++ % set.images.size();
    extractor.Extract(set.images[k], masked ? set.masks[k] : cv::Mat(), &features);
    keypoints += static_cast<double>(features.keypoints.size());
  }
  state.counters["keypoints"] = keypoints / static_cast<double>(state.iterations());
  Label(state, set, kitti);
}
BENCHMARK(BM_MoslamOrb)
    ->ArgsProduct({{0, 1}, {0, 1, 2, 3}})
    ->ArgNames({"vga", "masked"})
    ->Unit(benchmark::kMillisecond);

void BM_OpenCvOrb(benchmark::State& state) {
  const bool kitti = state.range(0) == 0;
  const ImageSet& set = Set(kitti);
  cv::Ptr<cv::ORB> orb =
      cv::ORB::create(set.features, 1.2f, 8, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31, 20);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  size_t i = 0;
  double count = 0;
  for (auto _ : state) {
    const size_t k = i++ % set.images.size();
    orb->detectAndCompute(set.images[k], cv::noArray(), keypoints, descriptors);
    count += static_cast<double>(keypoints.size());
  }
  state.counters["keypoints"] = count / static_cast<double>(state.iterations());
  Label(state, set, kitti);
}
BENCHMARK(BM_OpenCvOrb)->Arg(0)->Arg(1)->ArgName("vga")->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace moslam::feature
