// The networks shipped in data/models/, run through their cards exactly as `moslam run` and
// `moslam seg-eval` run them, on frames they were not trained on: a regression test of the
// models and of everything between an image and its mask (card, input size, normalization,
// softmax, CRF). The inputs are fixed (a seeded generator, the first CamVid val images), so the
// scores move only with floating-point differences between machines; the bounds sit 0.03-0.04
// below the measured scores (docs/WEAK.md and the cards give the full evaluations), under what
// the previous shipped models reach, so a broken card, an older model file or a refinement that
// inverts the mask fails them.
#include <filesystem>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/net/torch_mask_provider.h"
#include "moslam/synth/generator.h"
#include "moslam/testing/shared_data.h"

namespace moslam::net {
namespace {

namespace fs = std::filesystem;

// Binary IoU of masks against truth, summed over frames.
struct IoU {
  double tp = 0, fp = 0, fn = 0;
  void Add(const cv::Mat& mask, const cv::Mat& truth) {
    tp += cv::countNonZero(mask & truth);
    fp += cv::countNonZero(mask & ~truth);
    fn += cv::countNonZero(~mask & truth);
  }
  double Value() const { return tp / std::max(1.0, tp + fp + fn); }
};

std::unique_ptr<TorchMaskProvider> CardProvider(const std::string& path) {
  const semantic::ModelCard card = LoadAnyModelCard(path);
  semantic::RefineOptions refine = card.refine;
  refine.crf = semantic::CrfMode::kColour;
  return std::make_unique<TorchMaskProvider>(card, refine, 2);
}

TEST(ShippedModels, PersonCardFindsPeopleOnFramesOfAnUnseenSeed) {
  // Training frames of seed 12 (the card's held-out seed: other rooms, other textures than the
  // training seed 11), at the generator's default size.
  testing::TempDir dir;
  synth::GeneratorOptions options;
  options.seed = 12;
  options.out = dir.path();
  options.progress = false;
  synth::GenerateTraining(options, 24);
  auto provider = CardProvider("configs/models/weak_synth_person.yaml");
  IoU iou;
  for (int i = 0; i < 24; ++i) {
    const std::string stem = fmt::format("{:06d}.png", i);
    const cv::Mat image = cv::imread(dir.path() + "/rgb/" + stem);
    const cv::Mat classes =
        cv::imread(dir.path() + "/eval_only/class/" + stem, cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(image.empty());
    ASSERT_FALSE(classes.empty());
    const semantic::MaskResult result = provider->Segment({image, {}});
    ASSERT_EQ(result.mask.size(), image.size());
    iou.Add(result.mask > 0, classes == 1);
  }
  // Measured 0.803 (2026-12-01); the card's 200 held-out frames of this seed: 0.784. The
  // previous shipped network would score about 0.75 here, so the bound also catches a model
  // file swapped for an older one.
  ASSERT_GT(iou.tp, 0.0) << "no person found at all";
  EXPECT_GT(iou.Value(), 0.77);
}

TEST(ShippedModels, CamVidCardFindsCarsAndPeopleOnValidationImages) {
  MOSLAM_SHARED_OR_SKIP(root, "data/camvid/val");
  std::vector<fs::path> images;
  for (const auto& e : fs::directory_iterator(root)) images.push_back(e.path());
  std::sort(images.begin(), images.end());
  images.resize(std::min<size_t>(images.size(), 20));
  auto provider = CardProvider("configs/models/weak_camvid.yaml");
  IoU colour, grey;
  for (const fs::path& path : images) {
    const cv::Mat image = cv::imread(path.string());
    const cv::Mat ids =
        cv::imread((fs::path(root).parent_path() / "valannot" / path.stem()).string() + ".png",
                   cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(image.empty());
    ASSERT_FALSE(ids.empty()) << path;
    // Car, Pedestrian, Bicyclist; unlabelled pixels (11) are left out of both counts.
    const cv::Mat movable = (ids == 8) | (ids == 9) | (ids == 10);
    const cv::Mat counted = ids != 11;
    colour.Add((provider->Segment({image, {}}).mask > 0) & counted, movable);
    cv::Mat image_grey;
    cv::cvtColor(image, image_grey, cv::COLOR_BGR2GRAY);
    grey.Add((provider->Segment({image_grey, {}}).mask > 0) & counted, movable);
  }
  // Measured 0.616 and 0.608 on these 20 images (2026-12-01; the card, all 101: 0.601 and
  // 0.581 with this CRF); the previous network scored 0.588 and 0.578 here.
  EXPECT_GT(colour.Value(), 0.58);
  EXPECT_GT(grey.Value(), 0.57);
}

}  // namespace
}  // namespace moslam::net
