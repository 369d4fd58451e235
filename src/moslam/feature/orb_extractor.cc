#include "moslam/feature/orb_extractor.h"

#include <algorithm>
#include <cmath>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::feature {
namespace {

// FAST needs 3 pixels on each side of a candidate (its Bresenham circle has radius 3). Detection
// windows start this far inside the keypoint margin, so corners land at >= kOrbEdgeMargin.
constexpr int kFastRadius = 3;
constexpr int kDetectionBorder = kOrbEdgeMargin - kFastRadius;
// Smallest input accepted: the coarse levels must still leave room for the keypoint margins.
constexpr int kMinImageSide = 64;

// ORB-SLAM2's split of the budget over levels: a geometric series with ratio 1 / scale_factor
// (the same as OpenCV's ORB), so coarser, smaller levels get fewer keypoints; the last level takes
// what rounding left over.
std::vector<int> LevelQuotas(const OrbExtractorOptions& options) {
  const int levels = options.num_levels;
  std::vector<int> quota(levels, 0);
  const double ratio = 1.0 / options.scale_factor;
  double desired =
      options.num_features * (1.0 - ratio) / (1.0 - std::pow(ratio, static_cast<double>(levels)));
  int sum = 0;
  for (int l = 0; l + 1 < levels; ++l) {
    quota[l] = std::min(static_cast<int>(std::lround(desired)), options.num_features - sum);
    sum += quota[l];
    desired *= ratio;
  }
  quota[levels - 1] = std::max(options.num_features - sum, 0);
  return quota;
}

}  // namespace

OrbExtractor::OrbExtractor(const OrbExtractorOptions& options) : options_(options) {
  options_.Check();
  const int levels = options_.num_levels;
  scale_.resize(levels);
  inv_scale_.resize(levels);
  sigma2_.resize(levels);
  inv_sigma2_.resize(levels);
  for (int l = 0; l < levels; ++l) {
    const double scale = std::pow(options_.scale_factor, static_cast<double>(l));
    scale_[l] = static_cast<float>(scale);
    inv_scale_[l] = static_cast<float>(1.0 / scale);
    sigma2_[l] = static_cast<float>(scale * scale);
    inv_sigma2_[l] = static_cast<float>(1.0 / (scale * scale));
  }
  quota_ = LevelQuotas(options_);
  levels_.resize(levels);
  if (options_.mask_dilation_px > 0) {
    const int side = 2 * options_.mask_dilation_px + 1;
    dilation_kernel_ = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(side, side));
  }
}

OrbFeatures OrbExtractor::Extract(const cv::Mat& image, const cv::Mat& mask) {
  OrbFeatures features;
  Extract(image, mask, &features);
  return features;
}

void OrbExtractor::Extract(const cv::Mat& image, const cv::Mat& mask, OrbFeatures* features) {
  MOSLAM_CHECK(features != nullptr);
  CheckInputs(image, mask);
  BuildPyramid(image);
  const cv::Mat& movable = PrepareMask(mask);
  masked_keypoints_.clear();
  // Coarse to fine, so that a level short of candidates hands its unused quota to the next finer
  // level, which has more corners.
  int carry = 0;
  for (int l = options_.num_levels - 1; l >= 0; --l) {
    Level& level = levels_[l];
    DetectCandidates(l, movable);
    const int wanted = quota_[l] + carry;
    level.selected.clear();
    if (!level.candidates.empty()) {
      distributor_.Distribute(
          &level.candidates, kDetectionBorder,
          static_cast<float>(level.image.cols - kDetectionBorder), kDetectionBorder,
          static_cast<float>(level.image.rows - kDetectionBorder), wanted, &level.selected);
    }
    carry = wanted - static_cast<int>(level.selected.size());
    if (keep_masked_ && !level.masked.empty()) CollectMasked(l, wanted, movable);
  }
  Describe(features);
}

void OrbExtractor::CollectMasked(int level_index, int wanted, const cv::Mat& mask) {
  Level& level = levels_[level_index];
  // The threshold of each cell was chosen before the mask (DetectCandidates), so the unmasked
  // extractor's candidates are exactly the kept ones and the masked ones together.
  all_candidates_ = level.candidates;
  all_candidates_.insert(all_candidates_.end(), level.masked.begin(), level.masked.end());
  distributor_.Distribute(&all_candidates_, kDetectionBorder,
                          static_cast<float>(level.image.cols - kDetectionBorder), kDetectionBorder,
                          static_cast<float>(level.image.rows - kDetectionBorder), wanted,
                          &all_selected_);
  const float scale = scale_[level_index];
  for (const Candidate& c : all_selected_) {
    const int col = std::min(cvRound(c.x * scale), mask.cols - 1);
    const int row = std::min(cvRound(c.y * scale), mask.rows - 1);
    if (mask.ptr<uint8_t>(row)[col] != 0) masked_keypoints_.emplace_back(c.x * scale, c.y * scale);
  }
}

void OrbExtractor::CheckInputs(const cv::Mat& image, const cv::Mat& mask) const {
  if (image.empty()) ThrowInput("ORB extractor: the image is empty");
  if (image.type() != CV_8UC1) {
    ThrowInput(
        "ORB extractor: the image must be 8-bit single-channel (CV_8UC1), got {} channel(s) "
        "of depth {}",
        image.channels(), image.depth());
  }
  if (image.cols < kMinImageSide || image.rows < kMinImageSide) {
    ThrowInput("ORB extractor: the image is {}x{}, smaller than the minimum {}x{}", image.cols,
               image.rows, kMinImageSide, kMinImageSide);
  }
  if (mask.empty()) return;
  if (mask.type() != CV_8UC1) {
    ThrowInput(
        "ORB extractor: the movable-object mask must be 8-bit single-channel (CV_8UC1), got "
        "{} channel(s) of depth {}",
        mask.channels(), mask.depth());
  }
  if (mask.size() != image.size()) {
    ThrowInput("ORB extractor: the movable-object mask is {}x{} but the image is {}x{}", mask.cols,
               mask.rows, image.cols, image.rows);
  }
}

void OrbExtractor::BuildPyramid(const cv::Mat& image) {
  levels_[0].image = image;
  for (int l = 1; l < options_.num_levels; ++l) {
    const cv::Size size(static_cast<int>(std::lround(image.cols * inv_scale_[l])),
                        static_cast<int>(std::lround(image.rows * inv_scale_[l])));
    if (levels_[l - 1].image.empty() || size.width < 2 * kOrbEdgeMargin + 1 ||
        size.height < 2 * kOrbEdgeMargin + 1) {
      levels_[l].image = cv::Mat();  // too small to hold a keypoint: no detection there
      continue;
    }
    // Each level from the previous one, as ORB-SLAM2 does; resize reuses the level's buffer when
    // the size is unchanged.
    cv::resize(levels_[l - 1].image, levels_[l].image, size, 0, 0, cv::INTER_LINEAR);
  }
}

const cv::Mat& OrbExtractor::PrepareMask(const cv::Mat& mask) {
  if (mask.empty() || options_.mask_dilation_px == 0) return mask;
  cv::dilate(mask, dilated_mask_, dilation_kernel_);
  return dilated_mask_;
}

void OrbExtractor::DetectCandidates(int level_index, const cv::Mat& mask) {
  Level& level = levels_[level_index];
  level.candidates.clear();
  level.masked.clear();
  const cv::Mat& image = level.image;
  const int width = image.cols - 2 * kDetectionBorder;
  const int height = image.rows - 2 * kDetectionBorder;
  if (width <= 2 * kFastRadius || height <= 2 * kFastRadius) return;  // level too small

  // Grid as ORB-SLAM2: cells of about cell_size_px, each detecting in its own rectangle plus the
  // FAST radius around it.
  const int cell = options_.cell_size_px;
  const int cols = std::max(1, width / cell);
  const int rows = std::max(1, height / cell);
  const int cell_w = (width + cols - 1) / cols;
  const int cell_h = (height + rows - 1) / rows;

  // One FAST pass over the whole detection area at the initial threshold finds the same corners
  // as a pass per cell (up to non-maximum suppression across cell borders), with far less
  // per-call overhead; the fallback threshold then runs only in the cells that came up empty.
  const cv::Rect area(kDetectionBorder, kDetectionBorder, width, height);
  cv::FAST(image(area), fast_, options_.ini_th_fast, true, cv::FastFeatureDetector::TYPE_9_16);
  cell_count_.assign(static_cast<size_t>(rows) * cols, 0);
  for (const cv::KeyPoint& kp : fast_) {
    const int cx = std::min(static_cast<int>(kp.pt.x - kFastRadius) / cell_w, cols - 1);
    const int cy = std::min(static_cast<int>(kp.pt.y - kFastRadius) / cell_h, rows - 1);
    ++cell_count_[cy * cols + cx];
  }
  AppendCorners(level_index, kDetectionBorder, kDetectionBorder, mask);

  // Fallback threshold in the empty cells. A run of empty cells along a grid row is searched in
  // one call: FAST's fixed cost per call dominates in small windows, and sky or road often leaves
  // long runs.
  const int max_x = image.cols - kDetectionBorder;
  const int max_y = image.rows - kDetectionBorder;
  for (int cy = 0; cy < rows; ++cy) {
    const int y0 = kDetectionBorder + cy * cell_h;
    if (y0 >= max_y - 2 * kFastRadius) continue;
    const int y1 = std::min(y0 + cell_h + 2 * kFastRadius, max_y);
    for (int cx = 0; cx < cols;) {
      if (cell_count_[cy * cols + cx] > 0) {
        ++cx;
        continue;
      }
      int run_end = cx + 1;
      while (run_end < cols && cell_count_[cy * cols + run_end] == 0) ++run_end;
      const int x0 = kDetectionBorder + cx * cell_w;
      const int x1 = std::min(kDetectionBorder + run_end * cell_w + 2 * kFastRadius, max_x);
      cx = run_end;
      if (x0 >= max_x - 2 * kFastRadius) continue;
      cv::FAST(image(cv::Rect(x0, y0, x1 - x0, y1 - y0)), fast_, options_.min_th_fast, true,
               cv::FastFeatureDetector::TYPE_9_16);
      AppendCorners(level_index, x0, y0, mask);
    }
  }
}

void OrbExtractor::AppendCorners(int level_index, int offset_x, int offset_y, const cv::Mat& mask) {
  std::vector<Candidate>& out = levels_[level_index].candidates;
  if (mask.empty()) {
    for (const cv::KeyPoint& kp : fast_) {
      out.push_back({kp.pt.x + offset_x, kp.pt.y + offset_y, kp.response});
    }
    return;
  }
  // The paper's change: a candidate on a movable object never competes in the distribution. The
  // test is one byte lookup at the candidate's level-0 position.
  const float scale = scale_[level_index];
  const int max_col = mask.cols - 1;
  const int max_row = mask.rows - 1;
  for (const cv::KeyPoint& kp : fast_) {
    const float x = kp.pt.x + offset_x;
    const float y = kp.pt.y + offset_y;
    const int col = std::min(cvRound(x * scale), max_col);
    const int row = std::min(cvRound(y * scale), max_row);
    if (mask.ptr<uint8_t>(row)[col] != 0) {
      if (keep_masked_) levels_[level_index].masked.push_back({x, y, kp.response});
      continue;
    }
    out.push_back({x, y, kp.response});
  }
}

void OrbExtractor::Describe(OrbFeatures* features) {
  size_t total = 0;
  for (const Level& level : levels_) total += level.selected.size();
  features->keypoints.resize(total);
  features->descriptors.create(static_cast<int>(total), kOrbDescriptorBytes, CV_8U);
  int row = 0;
  for (int l = 0; l < options_.num_levels; ++l) {
    Level& level = levels_[l];
    if (level.selected.empty()) continue;
    // ORB's descriptor tests compare single pixels, so they are taken on a smoothed image to be
    // robust to noise (Rublee et al.: 7x7 Gaussian, sigma 2). The orientation uses the raw level.
    cv::GaussianBlur(level.image, level.smoothed, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
    const float scale = scale_[l];
    const float size = kOrbPatchSize * scale;
    for (const Candidate& c : level.selected) {
      const int x = static_cast<int>(c.x);
      const int y = static_cast<int>(c.y);
      const float angle = IntensityCentroidAngle(level.image, x, y);
      SteeredBrief(level.smoothed, x, y, angle, features->descriptors.ptr<uint8_t>(row));
      features->keypoints[row] = cv::KeyPoint(c.x * scale, c.y * scale, size, angle, c.response, l);
      ++row;
    }
  }
}

}  // namespace moslam::feature
