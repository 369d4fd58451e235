// Masks with controlled damage (mask_damage.h).
#include "moslam/runner/mask_damage.h"

#include <cmath>
#include <random>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "moslam/util/error.h"
#include "moslam/util/strings.h"

namespace moslam::runner {

void MaskDamageOptions::Check() const {
  if (!(miss >= 0.0 && miss <= 1.0)) ThrowInput("--mask-damage miss={}: must be in 0..1", miss);
  if (!(holes >= 0.0 && holes <= 1.0)) {
    ThrowInput("--mask-damage holes={}: must be in 0..1", holes);
  }
  if (border_px < 0) ThrowInput("--mask-damage border={}: must be >= 0", border_px);
  if (erode_px < 0) ThrowInput("--mask-damage erode={}: must be >= 0", erode_px);
  if (hole_radius_px < 1) ThrowInput("--mask-damage radius={}: must be >= 1", hole_radius_px);
}

MaskDamageOptions ParseMaskDamage(const std::string& spec) {
  MaskDamageOptions options;
  // Fields come split on commas and blanks, non-empty.
  for (const std::string_view field : SplitFields(spec, true)) {
    const size_t eq = field.find('=');
    if (eq == std::string_view::npos) {
      ThrowInput(
          "--mask-damage: '{}' is not key=value (keys: miss, border, erode, holes, "
          "radius, seed)",
          field);
    }
    const std::string key(field.substr(0, eq));
    const std::string_view value = field.substr(eq + 1);
    const auto number = ParseDouble(value);
    if (!number) ThrowInput("--mask-damage {}: '{}' is not a number", key, value);
    const auto whole = [&] {
      if (*number != std::floor(*number) || *number < 0) {
        ThrowInput("--mask-damage {}: '{}' is not a whole number >= 0", key, value);
      }
      return static_cast<int64_t>(*number);
    };
    if (key == "miss") {
      options.miss = *number;
    } else if (key == "border") {
      options.border_px = static_cast<int>(whole());
    } else if (key == "erode") {
      options.erode_px = static_cast<int>(whole());
    } else if (key == "holes") {
      options.holes = *number;
    } else if (key == "radius") {
      options.hole_radius_px = static_cast<int>(whole());
    } else if (key == "seed") {
      options.seed = static_cast<uint64_t>(whole());
    } else {
      ThrowInput("--mask-damage: unknown key '{}' (miss, border, erode, holes, radius, seed)", key);
    }
  }
  options.Check();
  return options;
}

cv::Mat DamageMask(const cv::Mat& mask, int frame_index, const MaskDamageOptions& options) {
  if (mask.empty() || !options.Any()) return mask;
  // One generator per frame, from the seed and the index only (splitmix-style mixing).
  std::mt19937_64 rng(options.seed * 0x9E3779B97F4A7C15ULL + static_cast<uint64_t>(frame_index));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  if (options.miss > 0.0 && unit(rng) < options.miss) return cv::Mat::zeros(mask.size(), CV_8UC1);
  cv::Mat out;
  cv::threshold(mask, out, 0, 255, cv::THRESH_BINARY);
  if (options.erode_px > 0) {
    const int k = 2 * options.erode_px + 1;
    cv::erode(out, out, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
  }
  if (options.border_px > 0) {  // only the inner rectangle is kept
    const int b = options.border_px;
    cv::Mat kept = cv::Mat::zeros(out.size(), CV_8UC1);
    const cv::Rect inner =
        cv::Rect(b, b, out.cols - 2 * b, out.rows - 2 * b) & cv::Rect(0, 0, out.cols, out.rows);
    if (inner.area() > 0) out(inner).copyTo(kept(inner));
    out = kept;
  }
  if (options.holes > 0.0) {
    std::vector<cv::Point> pixels;
    cv::findNonZero(out, pixels);
    const double disc = M_PI * options.hole_radius_px * options.hole_radius_px;
    const int count = static_cast<int>(std::ceil(options.holes * pixels.size() / disc));
    if (!pixels.empty()) {
      std::uniform_int_distribution<size_t> pick(0, pixels.size() - 1);
      for (int i = 0; i < count; ++i) {
        cv::circle(out, pixels[pick(rng)], options.hole_radius_px, cv::Scalar(0), cv::FILLED);
      }
    }
  }
  return out;
}

namespace {

class DamagedMaskSource : public MaskSource {
 public:
  DamagedMaskSource(std::unique_ptr<MaskSource> inner, const MaskDamageOptions& options)
      : inner_(std::move(inner)), options_(options) {}

  FrameMask MaskFor(const io::FrameEntry& frame, const cv::Size& image_size) const override {
    FrameMask mask = inner_->MaskFor(frame, image_size);
    Damage(&mask, frame.index);
    return mask;
  }
  bool Pipelined() const override { return inner_->Pipelined(); }
  FrameMask Predict(const io::FrameEntry& frame, const cv::Mat& image,
                    const cv::Mat& depth) override {
    FrameMask mask = inner_->Predict(frame, image, depth);
    mask.frame_index = frame.index;
    if (!inner_->Pipelined()) Damage(&mask, frame.index);
    return mask;
  }
  void Refine(FrameMask* mask, const cv::Mat& image, const cv::Mat& depth) override {
    inner_->Refine(mask, image, depth);
    if (inner_->Pipelined()) Damage(mask, mask->frame_index);
  }
  std::string Describe() const override {
    return fmt::format(
        "{}, damaged (miss {}, border {} px, erode {} px, holes {} of r {} px, "
        "seed {})",
        inner_->Describe(), options_.miss, options_.border_px, options_.erode_px, options_.holes,
        options_.hole_radius_px, options_.seed);
  }

 private:
  void Damage(FrameMask* mask, int index) const {
    mask->mask = DamageMask(mask->mask, index, options_);
    if (!mask->mask.empty()) {
      mask->fraction = static_cast<double>(cv::countNonZero(mask->mask)) /
                       static_cast<double>(mask->mask.total());
    }
  }

  std::unique_ptr<MaskSource> inner_;
  MaskDamageOptions options_;
};

}  // namespace

std::unique_ptr<MaskSource> MakeDamagedMaskSource(std::unique_ptr<MaskSource> inner,
                                                  const MaskDamageOptions& options) {
  options.Check();
  if (!options.Any()) return inner;
  return std::make_unique<DamagedMaskSource>(std::move(inner), options);
}

}  // namespace moslam::runner
