#include "moslam/semantic/mask_refine.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "moslam/semantic/input_limits.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/yaml.h"

namespace moslam::semantic {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

cv::Mat NewPlanar(int labels, const cv::Size& size) {
  const int sizes[3] = {labels, size.height, size.width};
  return cv::Mat(3, sizes, CV_32F);
}

cv::Size PlanarSize(const cv::Mat& planar) { return cv::Size(planar.size[2], planar.size[1]); }

// Grey or BGR 8-bit for the CRF (it ignores channel order; BGRA loses its alpha).
cv::Mat CrfImage(const cv::Mat& image) {
  if (image.type() != CV_8UC4) return image;
  cv::Mat bgr;
  cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
  return bgr;
}

}  // namespace

const char* ToString(CrfMode mode) {
  switch (mode) {
    case CrfMode::kNone:
      return "none";
    case CrfMode::kColour:
      return "c";
    case CrfMode::kDepth:
      return "d";
    case CrfMode::kColourDepth:
      return "cd";
  }
  return "?";
}

std::optional<CrfMode> ParseCrfMode(const std::string& text) {
  const std::string lower = ToLower(text);
  if (lower == "none") return CrfMode::kNone;
  if (lower == "c") return CrfMode::kColour;
  if (lower == "d") return CrfMode::kDepth;
  if (lower == "cd" || lower == "c,d") return CrfMode::kColourDepth;
  return std::nullopt;
}

void RefineOptions::Check() const {
  if (working_side < 0) ThrowInput("refine.working_side: must be >= 0, got {}", working_side);
  if (!(suppress_below >= 0.0f && suppress_below < 1.0f)) {
    ThrowInput("refine.suppress_below: must be in [0, 1), got {}", suppress_below);
  }
  if (!(std::abs(movable_bias) <= 10.0f)) {
    ThrowInput("refine.movable_bias: must be in [-10, 10] (nats), got {}", movable_bias);
  }
  if (dilate_px < 0 || dilate_px > kMaxDilatePx) {
    ThrowInput("refine.dilate_px: must be in [0, {}] pixels, got {}", kMaxDilatePx, dilate_px);
  }
  crf_options.Check();
}

void ReadRefineOptions(YamlFile& file, const std::string& prefix, RefineOptions* options) {
  file.Read(prefix + "working_side", &options->working_side);
  file.Read(prefix + "suppress_below", &options->suppress_below);
  file.Read(prefix + "crf_binary", &options->crf_binary);
  file.Read(prefix + "movable_bias", &options->movable_bias);
  file.Read(prefix + "dilate_px", &options->dilate_px);
  ReadDenseCrfOptions(file, "crf.", &options->crf_options);
}

cv::Size WorkingSize(const cv::Size& image_size, int working_side) {
  const int longest = std::max(image_size.width, image_size.height);
  if (working_side <= 0 || working_side >= longest) return image_size;
  const double scale = static_cast<double>(working_side) / longest;
  return cv::Size(std::max(1, static_cast<int>(std::lround(image_size.width * scale))),
                  std::max(1, static_cast<int>(std::lround(image_size.height * scale))));
}

cv::Mat ResizePlanar(const cv::Mat& planar, const cv::Size& size, int interpolation) {
  MOSLAM_CHECK(planar.dims == 3 && planar.type() == CV_32F) << "expected planar {L, H, W} CV_32F";
  if (PlanarSize(planar) == size) return planar;
  cv::Mat out = NewPlanar(planar.size[0], size);
  for (int l = 0; l < planar.size[0]; ++l) {
    cv::Mat plane = LabelPlane(out, l);
    cv::resize(LabelPlane(planar, l), plane, size, 0, 0, interpolation);
  }
  return out;
}

void SoftmaxPlanar(cv::Mat* planar) {
  MOSLAM_CHECK(planar->dims == 3 && planar->type() == CV_32F) << "expected planar CV_32F";
  const int labels = planar->size[0];
  cv::Mat top = LabelPlane(*planar, 0).clone();
  for (int l = 1; l < labels; ++l) top = cv::max(top, LabelPlane(*planar, l));
  cv::Mat sum(top.size(), CV_32F, cv::Scalar(0));
  for (int l = 0; l < labels; ++l) {
    cv::Mat plane = LabelPlane(*planar, l);
    cv::subtract(plane, top, plane);
    cv::exp(plane, plane);
    sum += plane;
  }
  for (int l = 0; l < labels; ++l) {
    cv::Mat plane = LabelPlane(*planar, l);
    cv::divide(plane, sum, plane);
  }
}

cv::Mat ArgMaxPlanar(const cv::Mat& planar) {
  cv::Mat labels(planar.size[1], planar.size[2], CV_8U, cv::Scalar(0));
  cv::Mat best = LabelPlane(planar, 0).clone();
  for (int l = 1; l < planar.size[0]; ++l) {
    const cv::Mat plane = LabelPlane(planar, l);
    const cv::Mat better = plane > best;
    labels.setTo(l, better);
    plane.copyTo(best, better);
  }
  return labels;
}

std::vector<float> PlaneMaxima(const cv::Mat& planar) {
  std::vector<float> maxima(planar.size[0]);
  for (int l = 0; l < planar.size[0]; ++l) {
    double top = 0.0;
    cv::minMaxLoc(LabelPlane(planar, l), nullptr, &top);
    maxima[l] = static_cast<float>(top);
  }
  return maxima;
}

MaskRefiner::MaskRefiner(const RefineOptions& options, std::vector<bool> movable, int background)
    : options_(options), movable_(std::move(movable)), background_(background) {
  options_.Check();
  MOSLAM_CHECK(movable_.size() >= 2 && movable_.size() <= 255) << "2..255 classes expected";
  MOSLAM_CHECK(background_ < static_cast<int>(movable_.size()));
  if (options_.crf != CrfMode::kNone) {
    options_.crf_options.appearance =
        options_.crf == CrfMode::kColour || options_.crf == CrfMode::kColourDepth;
    options_.crf_options.depth =
        options_.crf == CrfMode::kDepth || options_.crf == CrfMode::kColourDepth;
    if (!options_.crf_binary && movable_.size() > 32) {
      ThrowInput("refine.crf_binary: the CRF takes at most 32 labels, the model has {}",
                 movable_.size());
    }
    DenseCrfOptions check = options_.crf_options;  // built per image scale in ScaledCrf
    check.Check();
  }
}

DenseCrf& MaskRefiner::ScaledCrf(double scale) {
  if (!crf_ || crf_scale_ != scale) {
    // The kernels' spatial sigmas are given in pixels of the full image (as for `moslam crf` and
    // the published settings); at the working resolution the same neighbourhood is `scale` times
    // as many pixels wide. Without this, a 320-pixel working image would smooth over a third of
    // the picture with sxy = 80 and erase small objects.
    DenseCrfOptions o = options_.crf_options;
    o.smoothness_sxy = std::max(0.5f, static_cast<float>(o.smoothness_sxy * scale));
    o.appearance_sxy = std::max(0.5f, static_cast<float>(o.appearance_sxy * scale));
    o.depth_sxy = std::max(0.5f, static_cast<float>(o.depth_sxy * scale));
    crf_ = std::make_unique<DenseCrf>(o);
    crf_scale_ = scale;
  }
  return *crf_;
}

MaskRefiner::~MaskRefiner() = default;

RefineResult MaskRefiner::Refine(cv::Mat probabilities, const cv::Mat& image,
                                 const cv::Mat& depth_m, const std::vector<float>& image_scores) {
  const int labels = static_cast<int>(movable_.size());
  if (probabilities.dims != 3 || probabilities.type() != CV_32F ||
      probabilities.size[0] != labels) {
    ThrowInput("mask refinement: expected {} class planes of CV_32F, got {} dims with {}", labels,
               probabilities.dims, probabilities.dims == 3 ? probabilities.size[0] : 0);
  }
  if (image.empty()) ThrowInput("mask refinement: no image");
  const cv::Size working = WorkingSize(image.size(), options_.working_side);
  if (PlanarSize(probabilities) != working) {
    ThrowInput("mask refinement: scores are {}x{}, the working size is {}x{}",
               probabilities.size[2], probabilities.size[1], working.width, working.height);
  }
  if (!image_scores.empty() && static_cast<int>(image_scores.size()) != labels) {
    ThrowInput("mask refinement: {} image scores for {} classes", image_scores.size(), labels);
  }
  RefineResult result;
  result.image_scores = image_scores.empty() ? PlaneMaxima(probabilities) : image_scores;
  if (options_.suppress_below > 0.0f) {
    for (int l = 0; l < labels; ++l) {
      if (l == background_ || result.image_scores[l] >= options_.suppress_below) continue;
      LabelPlane(probabilities, l).setTo(0.0f);
      result.suppressed.push_back(l);
    }
    if (!result.suppressed.empty()) {
      cv::Mat sum(working, CV_32F, cv::Scalar(0));
      for (int l = 0; l < labels; ++l) sum += LabelPlane(probabilities, l);
      // Every class suppressed at a pixel (possible without a background class): uniform.
      const cv::Mat empty = sum <= 0.0f;
      for (int l = 0; l < labels; ++l) {
        cv::Mat plane = LabelPlane(probabilities, l);
        plane.setTo(1.0f, empty);
        cv::divide(plane, cv::max(sum, 1e-12f), plane);
      }
    }
  }
  if (options_.movable_bias != 0.0f) ShiftMovablePrior(&probabilities);
  result.labels = ArgMaxPlanar(probabilities);
  const cv::Mat movable_work =
      MovableAtWorkingSize(&probabilities, result.labels, image, depth_m, &result.crf_ms);
  if (!options_.crf_binary && options_.crf != CrfMode::kNone) {
    // The CRF's marginals replaced the network's probabilities in MovableAtWorkingSize.
    result.labels = ArgMaxPlanar(probabilities);
  }
  cv::Mat mask;
  if (movable_work.size() == image.size()) {
    mask = movable_work;
  } else {
    cv::resize(movable_work, mask, image.size(), 0, 0, cv::INTER_LINEAR);
    cv::threshold(mask, mask, 127, 255, cv::THRESH_BINARY);
  }
  if (options_.dilate_px > 0) {
    const int side = 2 * options_.dilate_px + 1;
    cv::dilate(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(side, side)));
  }
  result.probabilities = std::move(probabilities);
  result.mask = std::move(mask);
  return result;
}

void MaskRefiner::ShiftMovablePrior(cv::Mat* probabilities) const {
  const float factor = std::exp(options_.movable_bias);
  const cv::Size size = PlanarSize(*probabilities);
  cv::Mat sum(size, CV_32F, cv::Scalar(0));
  for (int l = 0; l < static_cast<int>(movable_.size()); ++l) {
    cv::Mat plane = LabelPlane(*probabilities, l);
    if (movable_[l]) plane *= factor;
    sum += plane;
  }
  for (int l = 0; l < static_cast<int>(movable_.size()); ++l) {
    cv::Mat plane = LabelPlane(*probabilities, l);
    cv::divide(plane, cv::max(sum, 1e-12f), plane);
  }
}

cv::Mat MaskRefiner::MovableAtWorkingSize(cv::Mat* probabilities, const cv::Mat& labels,
                                          const cv::Mat& image, const cv::Mat& depth_m,
                                          double* crf_ms) {
  const int num = static_cast<int>(movable_.size());
  cv::Mat lut(1, 256, CV_8U, cv::Scalar(0));
  for (int l = 0; l < num; ++l) lut.at<uint8_t>(0, l) = movable_[l] ? 255 : 0;
  if (options_.crf == CrfMode::kNone) {
    cv::Mat movable;
    cv::LUT(labels, lut, movable);
    return movable;
  }
  const auto start = Clock::now();
  const cv::Size working = PlanarSize(*probabilities);
  DenseCrf& crf_model = ScaledCrf(static_cast<double>(working.width) / image.cols);
  cv::Mat small_image;
  cv::resize(CrfImage(image), small_image, working, 0, 0, cv::INTER_AREA);
  cv::Mat small_depth;
  if (options_.crf_options.depth) {
    if (depth_m.empty() || depth_m.size() != image.size() || depth_m.type() != CV_32FC1) {
      ThrowInput("--crf {}: the depth kernel needs a CV_32F depth map of the image's size",
                 ToString(options_.crf));
    }
    // Nearest neighbour: averaging depth across an object's edge invents surfaces in between.
    cv::resize(depth_m, small_depth, working, 0, 0, cv::INTER_NEAREST);
  }
  cv::Mat movable;
  if (options_.crf_binary) {
    cv::Mat two = NewPlanar(2, working);
    LabelPlane(two, 0).setTo(0.0f);
    LabelPlane(two, 1).setTo(0.0f);
    for (int l = 0; l < num; ++l) {
      cv::Mat target = LabelPlane(two, movable_[l] ? 1 : 0);
      target += LabelPlane(*probabilities, l);
    }
    const CrfResult crf =
        crf_model.Infer(small_image, small_depth, Unaries::FromProbabilities(two));
    movable = crf.labels * 255;
  } else {
    const CrfResult crf =
        crf_model.Infer(small_image, small_depth, Unaries::FromProbabilities(*probabilities));
    *probabilities = crf.marginals;
    cv::LUT(crf.labels, lut, movable);
  }
  *crf_ms = MsSince(start);
  return movable;
}

}  // namespace moslam::semantic
