// `moslam features IMAGE [--mask M] [--n N] --out overlay.png [--keypoints kp.csv]`: runs the ORB
// extractor (moslam::feature) on one image, optionally with a movable-object mask, and draws the
// keypoints (circle radius grows with the pyramid level, a line shows the orientation) over the
// image with the mask tinted red; optionally writes the keypoints as CSV.
#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "moslam/feature/orb_extractor.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/util/error.h"

namespace moslam::app {
namespace {

struct FeaturesArgs {
  std::string image;
  std::string mask;
  std::string settings;
  std::string out;
  std::string keypoints;
  int num_features = 0;  // 0: from --settings or the default
  int dilation = 0;
};

cv::Mat ReadImage(const std::string& path, const char* what) {
  cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) ThrowInFile(path, fmt::format("cannot be read as an image ({})", what));
  return image;
}

// One colour per pyramid level (BGR), cycling for deep pyramids.
cv::Scalar LevelColour(int level) {
  static const cv::Scalar kColours[] = {{0, 255, 0},   {255, 255, 0},  {255, 128, 0},
                                        {255, 0, 255}, {0, 255, 255},  {0, 128, 255},
                                        {128, 0, 255}, {255, 255, 255}};
  return kColours[level % 8];
}

cv::Mat DrawOverlay(const cv::Mat& image, const cv::Mat& mask,
                    const feature::OrbFeatures& features) {
  cv::Mat overlay;
  cv::cvtColor(image, overlay, cv::COLOR_GRAY2BGR);
  if (!mask.empty()) {
    // Tint movable pixels red so that one sees that no keypoint lies on them.
    cv::Mat tinted = overlay.clone();
    tinted.setTo(cv::Scalar(0, 0, 255), mask);
    cv::addWeighted(overlay, 0.6, tinted, 0.4, 0, overlay);
  }
  for (const cv::KeyPoint& kp : features.keypoints) {
    const float radius = 3.0f * std::pow(1.2f, static_cast<float>(kp.octave)) + 1.0f;
    const float angle = kp.angle * static_cast<float>(CV_PI / 180.0);
    const cv::Point2f tip = kp.pt + radius * cv::Point2f(std::cos(angle), std::sin(angle));
    const cv::Scalar colour = LevelColour(kp.octave);
    // Sub-pixel drawing (shift 4) keeps circles of coarse levels centred.
    const cv::Point centre(cvRound(kp.pt.x * 16), cvRound(kp.pt.y * 16));
    cv::circle(overlay, centre, cvRound(radius * 16), colour, 1, cv::LINE_AA, 4);
    cv::line(overlay, centre, cv::Point(cvRound(tip.x * 16), cvRound(tip.y * 16)), colour, 1,
             cv::LINE_AA, 4);
  }
  return overlay;
}

void WriteKeypoints(const std::string& path, const feature::OrbFeatures& features) {
  std::ofstream out(path);
  if (!out) ThrowInFile(path, "cannot be written");
  out << "x,y,octave,angle,response\n";
  for (const cv::KeyPoint& kp : features.keypoints) {
    out << fmt::format("{:.2f},{:.2f},{},{:.3f},{:.1f}\n", kp.pt.x, kp.pt.y, kp.octave, kp.angle,
                       kp.response);
  }
  if (!out) ThrowInFile(path, "could not be written completely");
}

void RunFeatures(const FeaturesArgs& args) {
  feature::OrbExtractorOptions options;
  if (!args.settings.empty()) {
    options.ApplySettings(io::LoadOrbSlamSettings(args.settings, io::SensorType::kMonocular).orb);
  }
  if (args.num_features > 0) options.num_features = args.num_features;
  options.mask_dilation_px = args.dilation;
  options.Check();

  const cv::Mat image = ReadImage(args.image, "the image");
  cv::Mat mask;
  if (!args.mask.empty()) {
    mask = ReadImage(args.mask, "the movable-object mask");
    if (mask.size() != image.size()) {
      ThrowInFile(args.mask, fmt::format("mask is {}x{} but the image {} is {}x{}", mask.cols,
                                         mask.rows, args.image, image.cols, image.rows));
    }
  }

  feature::OrbExtractor extractor(options);
  const auto start = std::chrono::steady_clock::now();
  const feature::OrbFeatures features = extractor.Extract(image, mask);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::vector<int> per_level(options.num_levels, 0);
  for (const cv::KeyPoint& kp : features.keypoints) ++per_level[kp.octave];
  spdlog::info("{}: {} keypoints of {} wanted in {:.1f} ms (first call), per level: {}", args.image,
               features.keypoints.size(), options.num_features, ms, fmt::join(per_level, " "));
  if (static_cast<int>(features.keypoints.size()) < options.num_features) {
    spdlog::warn("fewer keypoints than wanted: the unmasked image has too few corners");
  }
  if (!mask.empty()) {
    spdlog::info("mask {}: {:.1f}% of the pixels movable, dilated by {} px", args.mask,
                 100.0 * cv::countNonZero(mask) / static_cast<double>(mask.total()),
                 options.mask_dilation_px);
  }

  // Show the mask the extractor used: grown by the dilation (same elliptic element).
  cv::Mat shown_mask = mask;
  if (!mask.empty() && options.mask_dilation_px > 0) {
    const int side = 2 * options.mask_dilation_px + 1;
    cv::dilate(mask, shown_mask,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(side, side)));
  }
  const cv::Mat overlay = DrawOverlay(image, shown_mask, features);
  bool written = false;
  try {
    written = cv::imwrite(args.out, overlay);
  } catch (const cv::Exception& e) {
    ThrowInFile(args.out, fmt::format("cannot be written: {}", e.err));
  }
  if (!written) ThrowInFile(args.out, "cannot be written (unknown image extension or folder?)");
  spdlog::info("overlay written to {}", args.out);
  if (!args.keypoints.empty()) {
    WriteKeypoints(args.keypoints, features);
    spdlog::info("keypoints written to {}", args.keypoints);
  }
}

}  // namespace

void AddFeaturesCommand(CLI::App& app) {
  auto args = std::make_shared<FeaturesArgs>();
  CLI::App* command = app.add_subcommand(
      "features",
      "Extract ORB features (ORB-SLAM2 style, with the optional movable-object mask) from one "
      "image and draw them");
  command->add_option("image", args->image, "Input image (read as grey)")
      ->required()
      ->check(CLI::ExistingFile);
  command
      ->add_option("--mask", args->mask,
                   "Movable-object mask image of the same size; non-zero pixels are movable and "
                   "get no keypoints (default: none)")
      ->check(CLI::ExistingFile);
  command->add_option("--n", args->num_features,
                      "Number of keypoints wanted (default: --settings' ORBextractor.nFeatures, "
                      "else 1000)");
  command
      ->add_option("--dilate", args->dilation,
                   "Grow the mask by this many pixels before dropping keypoints")
      ->capture_default_str();
  command
      ->add_option("--settings", args->settings,
                   "ORB-SLAM2 settings YAML; its ORBextractor.* keys are used (default: none)")
      ->check(ExistingFileOf("settings file"));
  command->add_option("--out", args->out, "Overlay image to write (PNG, JPEG, ...)")->required();
  command->add_option("--keypoints", args->keypoints,
                      "CSV file to write: x,y,octave,angle,response per keypoint, level-0 pixels "
                      "and degrees (default: none)");
  command->callback([args] { RunFeatures(*args); });
}

}  // namespace moslam::app
