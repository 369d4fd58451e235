// The ONNX segmentation and detector providers on the shared models and CamVid images (skipped
// with a message when MOSLAM_SHARED does not hold them): shapes, class mapping, mask polarity.
#include <filesystem>
#include <fstream>
#include <iterator>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/semantic/mask_provider.h"
#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::semantic {
namespace {

namespace fs = std::filesystem;

// The first CamVid val image (in name order) whose cars (label 8) cover at least 5 % of it.
struct Example {
  cv::Mat image;
  cv::Mat cars;  // CV_8U 255 where the label is car
};
Example FirstImageWithCars(const std::string& camvid) {
  std::vector<fs::path> names;
  for (const auto& e : fs::directory_iterator(camvid + "/valannot")) names.push_back(e.path());
  std::sort(names.begin(), names.end());
  for (const fs::path& annot : names) {
    const cv::Mat labels = cv::imread(annot.string(), cv::IMREAD_GRAYSCALE);
    const cv::Mat cars = labels == 8;
    if (cv::countNonZero(cars) < 0.05 * static_cast<double>(labels.total())) continue;
    const fs::path image = fs::path(camvid) / "val" / (annot.stem().string() + ".jpg");
    const fs::path png = fs::path(camvid) / "val" / (annot.stem().string() + ".png");
    Example e{cv::imread(fs::exists(image) ? image.string() : png.string()), cars};
    if (!e.image.empty()) return e;
  }
  return {};
}

double Iou(const cv::Mat& a, const cv::Mat& b) {
  return cv::countNonZero(a & b) / std::max(1.0, static_cast<double>(cv::countNonZero(a | b)));
}

TEST(OnnxSegmenter, DeepLabMarksTheCarsOfACamVidImageAsMovable) {
  MOSLAM_SHARED_OR_SKIP(model, "models/deeplabv3_mnv2_voc/deeplabv3_mnv2_voc.onnx");
  MOSLAM_SHARED_OR_SKIP(camvid, "data/camvid");
  const ModelCard card =
      LoadModelCard("configs/models/deeplabv3_mnv2_voc.yaml", ::moslam::testing::SharedRoot());
  const std::unique_ptr<MaskProvider> provider = MakeMaskProvider(card, card.refine);
  const Example example = FirstImageWithCars(camvid);
  ASSERT_FALSE(example.image.empty()) << "no CamVid val image with cars";
  const MaskResult r = provider->Segment({example.image, {}});
  ASSERT_EQ(r.mask.size(), example.image.size());
  ASSERT_EQ(r.mask.type(), CV_8UC1);
  EXPECT_EQ(cv::countNonZero((r.mask != 0) & (r.mask != 255)), 0) << "mask is 0 / 255";
  ASSERT_EQ(r.probabilities.dims, 3);
  EXPECT_EQ(r.probabilities.size[0], 21);
  EXPECT_EQ(cv::Size(r.probabilities.size[2], r.probabilities.size[1]),
            WorkingSize(example.image.size(), card.refine.working_side));
  // Class mapping: where the argmax is "car" (VOC 7) the mask is movable; where it is background
  // (0) it is not (compared at the working size).
  cv::Mat small;
  cv::resize(r.mask, small, r.labels.size(), 0, 0, cv::INTER_NEAREST);
  const cv::Mat car = r.labels == 7;
  ASSERT_GT(cv::countNonZero(car), 0) << "DeepLab found no car";
  EXPECT_GT(cv::countNonZero(small & car), 0.9 * cv::countNonZero(car));
  EXPECT_LT(cv::countNonZero(small & (r.labels == 0)), 0.1 * cv::countNonZero(r.labels == 0));
  // Polarity against the ground truth: the movable pixels are mostly the cars.
  EXPECT_GT(Iou(r.mask, example.cars), 0.3);
  EXPECT_GT(r.network_ms, 0.0);
  // A grey frame (KITTI's input) goes through the same network.
  cv::Mat grey;
  cv::cvtColor(example.image, grey, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(provider->Segment({grey, {}}).mask.size(), grey.size());
}

TEST(BoxDetector, YoloFastestBoxesCoverTheCarsOfACamVidImage) {
  MOSLAM_SHARED_OR_SKIP(model, "models/yolo_fastest_coco/yolo-fastest-1.1-xl.weights");
  MOSLAM_SHARED_OR_SKIP(camvid, "data/camvid");
  const ModelCard card =
      LoadModelCard("configs/models/yolo_fastest_coco.yaml", ::moslam::testing::SharedRoot());
  const std::unique_ptr<MaskProvider> provider = MakeMaskProvider(card, card.refine);
  EXPECT_EQ(provider->class_names().front(), "static");
  EXPECT_EQ(provider->class_names().size(), 1 + card.movable.size());
  const Example example = FirstImageWithCars(camvid);
  ASSERT_FALSE(example.image.empty());
  const MaskResult r = provider->Segment({example.image, {}});
  ASSERT_EQ(r.mask.size(), example.image.size());
  EXPECT_EQ(cv::countNonZero((r.mask != 0) & (r.mask != 255)), 0);
  const int car_class = 2;  // COCO "car"
  int cars = 0;
  for (const Detection& d : r.detections) {
    const bool movable = card.MovableFlags()[d.class_id];
    const cv::Mat inside = r.mask(d.box);
    if (movable) {
      // Every pixel of a movable box is masked (box masks, no CRF).
      EXPECT_EQ(cv::countNonZero(inside), static_cast<int>(d.box.area()))
          << card.classes[d.class_id];
    }
    cars += d.class_id == car_class ? 1 : 0;
  }
  EXPECT_GT(cars, 0) << "Yolo-Fastest found no car";
  // The boxes hold most car pixels (recall), though they cover background too.
  EXPECT_GT(cv::countNonZero(r.mask & example.cars), 0.5 * cv::countNonZero(example.cars));
}

// Issue 31: OpenCV's Darknet reader takes a short weights file without a word; the weights file
// is compared with what the network's layers hold.
TEST(BoxDetector, TruncatedDarknetWeightsAreRefused) {
  MOSLAM_SHARED_OR_SKIP(model, "models/yolo_fastest_coco/yolo-fastest-1.1-xl.weights");
  MOSLAM_SHARED_OR_SKIP(cfg, "models/yolo_fastest_coco/yolo-fastest-1.1-xl.cfg");
  ModelCard card =
      LoadModelCard("configs/models/yolo_fastest_coco.yaml", ::moslam::testing::SharedRoot());
  std::ifstream in(model, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(bytes.size(), 1000u);
  testing::TempDir dir;
  for (const size_t size : {size_t{100}, bytes.size() - 4}) {
    card.model = dir.Write("short.weights", bytes.substr(0, size));
    EXPECT_THAT(testing::ErrorOf([&] { MakeMaskProvider(card, card.refine); }),
                ::testing::AllOf(::testing::HasSubstr(card.model),
                                 ::testing::HasSubstr("yolo_fastest_coco.yaml"),
                                 ::testing::HasSubstr(std::to_string(size))))
        << size;
  }
}

}  // namespace
}  // namespace moslam::semantic
