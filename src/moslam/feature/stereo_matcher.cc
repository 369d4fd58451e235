#include "moslam/feature/stereo_matcher.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::feature {
namespace {

// For each image row, the right keypoints whose row band covers it.
std::vector<std::vector<int>> RowIndex(const OrbFeatures& right, const OrbExtractor& extractor,
                                       int rows, float band_scale) {
  std::vector<std::vector<int>> index(rows);
  for (int i = 0; i < static_cast<int>(right.keypoints.size()); ++i) {
    const cv::KeyPoint& kp = right.keypoints[i];
    const float r = band_scale * extractor.scale_factors()[kp.octave];
    const int lo = std::max(0, static_cast<int>(std::floor(kp.pt.y - r)));
    const int hi = std::min(rows - 1, static_cast<int>(std::ceil(kp.pt.y + r)));
    for (int row = lo; row <= hi; ++row) index[row].push_back(i);
  }
  return index;
}

// SAD of two patches after subtracting each patch's centre intensity, which makes the cost
// insensitive to a brightness offset between the cameras (as in ORB-SLAM2).
float PatchSad(const cv::Mat& left, int lx, const cv::Mat& right, int rx, int y, int w) {
  const int lc = left.at<uint8_t>(y, lx);
  const int rc = right.at<uint8_t>(y, rx);
  int sad = 0;
  for (int dy = -w; dy <= w; ++dy) {
    const uint8_t* l = left.ptr<uint8_t>(y + dy) + lx;
    const uint8_t* r = right.ptr<uint8_t>(y + dy) + rx;
    for (int dx = -w; dx <= w; ++dx) sad += std::abs((l[dx] - lc) - (r[dx] - rc));
  }
  return static_cast<float>(sad);
}

// SAD of two patches after subtracting each patch's mean intensity (zero-mean SAD): insensitive
// to a brightness offset between the cameras, and on level 0's larger windows less noisy than
// ORB-SLAM2's subtraction of the centre pixel, whose noise would shift every term.
int PatchZsad(const cv::Mat& left, int lx, const cv::Mat& right, int rx, int y, int w) {
  int lsum = 0, rsum = 0;
  for (int dy = -w; dy <= w; ++dy) {
    const uint8_t* l = left.ptr<uint8_t>(y + dy) + lx;
    const uint8_t* r = right.ptr<uint8_t>(y + dy) + rx;
    for (int dx = -w; dx <= w; ++dx) {
      lsum += l[dx];
      rsum += r[dx];
    }
  }
  const int n = (2 * w + 1) * (2 * w + 1);
  // Offset in 1/n grey levels, so the sums stay integers: n * (l - lmean) - n * (r - rmean).
  const int offset = rsum - lsum;
  int sad = 0;
  for (int dy = -w; dy <= w; ++dy) {
    const uint8_t* l = left.ptr<uint8_t>(y + dy) + lx;
    const uint8_t* r = right.ptr<uint8_t>(y + dy) + rx;
    for (int dx = -w; dx <= w; ++dx) sad += std::abs(n * (l[dx] - r[dx]) + offset);
  }
  return sad;
}

// Sub-pixel offset of a cost minimum from the costs s1, s2, s3 at -1, 0, +1 (s2 the smallest).
// False when the costs are flat or the offset leaves [-1, 1].
bool SubPixelOffset(float s1, float s2, float s3, SubPixelFit fit, float* delta) {
  if (fit == SubPixelFit::kParabola) {
    const float denom = 2.0f * (s1 + s3 - 2.0f * s2);
    if (!(denom > 0.0f)) return false;
    *delta = (s1 - s3) / denom;
  } else {
    // Lines of slopes -a and +a through the three points (Shimizu & Okutomi 2001): the steeper
    // side gives the slope, a = max(s1, s3) - s2, and the lines cross at (s1 - s3) / (2 a).
    const float a = std::max(s1, s3) - s2;
    if (!(a > 0.0f)) return false;
    *delta = (s1 - s3) / (2.0f * a);
  }
  return *delta >= -1.0f && *delta <= 1.0f;
}

struct Refined {
  float u_right;  // level-0 pixels
  float sad;      // SAD on the keypoint's level (the outlier step compares these)
};

// The minimum of `sads` (index 0 is offset -search) with its sub-pixel offset; false when it
// lies on the border, the fit fails, or (max_ratio < 1) another SAD at least two steps away is
// nearly as small.
bool SadMinimum(const std::vector<float>& sads, SubPixelFit fit, double max_ratio, float* offset,
                float* best_sad) {
  const int n = static_cast<int>(sads.size());
  const int best = static_cast<int>(std::min_element(sads.begin(), sads.end()) - sads.begin());
  if (best == 0 || best == n - 1) return false;
  if (max_ratio < 1.0) {
    float second = std::numeric_limits<float>::max();
    for (int i = 0; i < n; ++i) {
      if (std::abs(i - best) >= 2) second = std::min(second, sads[i]);
    }
    if (sads[best] > max_ratio * second) return false;
  }
  float delta = 0.0f;
  if (!SubPixelOffset(sads[best - 1], sads[best], sads[best + 1], fit, &delta)) return false;
  *offset = static_cast<float>(best - (n - 1) / 2) + delta;
  *best_sad = sads[best];
  return true;
}

// Step 3 of the header on the left keypoint's level: SAD search around the descriptor match, then
// the sub-pixel fit. sad < 0 when the window leaves the image, the minimum lies on the search
// border, the match is ambiguous or the sub-pixel offset is more than one pixel.
Refined RefineOnLevel(const cv::KeyPoint& left_kp, float u_right0, const OrbExtractor& left_ex,
                      const OrbExtractor& right_ex, const StereoMatchOptions& options) {
  const Refined failed{0.0f, -1.0f};
  const int level = left_kp.octave;
  const float inv_scale = left_ex.inv_scale_factors()[level];
  const cv::Mat& left_image = left_ex.level_image(level);
  const cv::Mat& right_image = right_ex.level_image(level);
  if (left_image.empty() || right_image.empty()) return failed;
  const int ul = static_cast<int>(std::lround(left_kp.pt.x * inv_scale));
  const int vl = static_cast<int>(std::lround(left_kp.pt.y * inv_scale));
  const int ur0 = static_cast<int>(std::lround(u_right0 * inv_scale));
  const int w = options.patch_half_size;
  const int search = options.search_half_width;
  if (vl - w < 0 || vl + w >= left_image.rows || ul - w < 0 || ul + w >= left_image.cols) {
    return failed;
  }
  if (ur0 - search - w < 0 || ur0 + search + w >= right_image.cols) return failed;
  std::vector<float> sads(2 * search + 1);
  for (int inc = -search; inc <= search; ++inc) {
    sads[inc + search] = PatchSad(left_image, ul, right_image, ur0 + inc, vl, w);
  }
  float offset = 0.0f, sad = 0.0f;
  if (!SadMinimum(sads, options.subpixel, options.max_sad_ratio, &offset, &sad)) return failed;
  return Refined{left_ex.scale_factors()[level] * (static_cast<float>(ur0) + offset), sad};
}

// The level's match refined on level 0 (issue 29): a window of patch_half_size * scale pixels (at
// most level0_max_half_size) around the level-0 position of the keypoint's level pixel,
// (x_l + 0.5) * W / w_l - 0.5 (the pixel centres of cv::resize), searched over +-(scale + 1)
// pixels around the level's disparity.
// The disparity found holds for that window's centre; the returned u_right keeps it relative to
// the keypoint's nominal x (x_l * scale), which the rest of the system uses.
Refined RefineOnLevel0(const cv::KeyPoint& left_kp, const Refined& coarse,
                       const OrbExtractor& left_ex, const OrbExtractor& right_ex,
                       const StereoMatchOptions& options) {
  const Refined failed{0.0f, -1.0f};
  const int level = left_kp.octave;
  const cv::Mat& left0 = left_ex.level_image(0);
  const cv::Mat& right0 = right_ex.level_image(0);
  const cv::Mat& left_level = left_ex.level_image(level);
  const float scale = left_ex.scale_factors()[level];
  const float inv_scale = left_ex.inv_scale_factors()[level];
  const double sx = static_cast<double>(left0.cols) / left_level.cols;
  const double sy = static_cast<double>(left0.rows) / left_level.rows;
  const double xl = std::round(left_kp.pt.x * inv_scale), yl = std::round(left_kp.pt.y * inv_scale);
  const int ul = static_cast<int>(std::lround((xl + 0.5) * sx - 0.5));
  const int vl = static_cast<int>(std::lround((yl + 0.5) * sy - 0.5));
  const float coarse_disparity = left_kp.pt.x - coarse.u_right;
  const int ur0 = static_cast<int>(std::lround(static_cast<float>(ul) - coarse_disparity));
  const int w = std::min(options.level0_max_half_size,
                         static_cast<int>(std::lround(options.patch_half_size * scale)));
  const int search = static_cast<int>(std::ceil(scale)) + 1;
  if (vl - w < 0 || vl + w >= left0.rows || ul - w < 0 || ul + w >= left0.cols) return failed;
  if (ur0 - search - w < 0 || ur0 + search + w >= right0.cols) return failed;
  std::vector<float> sads(2 * search + 1);
  for (int inc = -search; inc <= search; ++inc) {
    sads[inc + search] = static_cast<float>(PatchZsad(left0, ul, right0, ur0 + inc, vl, w));
  }
  float offset = 0.0f, unused = 0.0f;
  if (!SadMinimum(sads, options.subpixel, 1.0, &offset, &unused)) return failed;
  const float disparity = static_cast<float>(ul) - (static_cast<float>(ur0) + offset);
  return Refined{left_kp.pt.x - disparity, coarse.sad};
}

Refined RefineBySad(const cv::KeyPoint& left_kp, float u_right0, const OrbExtractor& left_ex,
                    const OrbExtractor& right_ex, const StereoMatchOptions& options) {
  const Refined coarse = RefineOnLevel(left_kp, u_right0, left_ex, right_ex, options);
  if (coarse.sad < 0.0f || !options.refine_at_level0) return coarse;
  return RefineOnLevel0(left_kp, coarse, left_ex, right_ex, options);
}

}  // namespace

void StereoMatchOptions::Check() const {
  if (max_descriptor_distance < 0 || max_descriptor_distance > 256) {
    ThrowInput("stereo option max_descriptor_distance must be in [0, 256] (got {})",
               max_descriptor_distance);
  }
  if (!(row_band_scale > 0.0f)) ThrowInput("stereo option row_band_scale must be > 0");
  if (patch_half_size < 1) ThrowInput("stereo option patch_half_size must be >= 1");
  if (search_half_width < 1) ThrowInput("stereo option search_half_width must be >= 1");
  if (level0_max_half_size < 1) ThrowInput("stereo option level0_max_half_size must be >= 1");
  if (!(min_depth_baselines > 0.0)) ThrowInput("stereo option min_depth_baselines must be > 0");
  if (!(outlier_factor > 0.0)) ThrowInput("stereo option outlier_factor must be > 0");
  if (!(max_sad_ratio >= 0.0 && max_sad_ratio <= 1.0)) {
    ThrowInput("stereo option max_sad_ratio must be in [0, 1] (got {})", max_sad_ratio);
  }
}

StereoMatches MatchStereo(const OrbFeatures& left, const OrbExtractor& left_extractor,
                          const OrbFeatures& right, const OrbExtractor& right_extractor, double bf,
                          double fx, const StereoMatchOptions& options) {
  MOSLAM_CHECK(bf > 0.0 && fx > 0.0) << "bf " << bf << " fx " << fx;
  options.Check();
  const size_t n = left.keypoints.size();
  StereoMatches result;
  result.u_right.assign(n, -1.0f);
  result.depth.assign(n, -1.0f);
  result.right_index.assign(n, -1);
  const int rows = left_extractor.level_image(0).rows;
  if (n == 0 || right.keypoints.empty() || rows == 0) return result;

  const auto row_index = RowIndex(right, right_extractor, rows, options.row_band_scale);
  const float min_d = 0.0f;
  const float max_d = static_cast<float>(fx / options.min_depth_baselines);
  std::vector<std::pair<float, int>> sad_and_index;
  sad_and_index.reserve(n);

  for (size_t i = 0; i < n; ++i) {
    const cv::KeyPoint& kl = left.keypoints[i];
    const int row = static_cast<int>(kl.pt.y);
    if (row < 0 || row >= rows) continue;
    const float min_u = kl.pt.x - max_d, max_u = kl.pt.x - min_d;
    if (max_u < 0.0f) continue;
    const uint8_t* dl = left.descriptors.ptr<uint8_t>(static_cast<int>(i));
    int best_dist = options.max_descriptor_distance, best_j = -1;
    for (const int j : row_index[row]) {
      const cv::KeyPoint& kr = right.keypoints[j];
      if (kr.octave < kl.octave - 1 || kr.octave > kl.octave + 1) continue;
      if (kr.pt.x < min_u || kr.pt.x > max_u) continue;
      const int dist = DescriptorDistance(dl, right.descriptors.ptr<uint8_t>(j));
      if (dist < best_dist) {
        best_dist = dist;
        best_j = j;
      }
    }
    if (best_j < 0) continue;
    const Refined refined =
        RefineBySad(kl, right.keypoints[best_j].pt.x, left_extractor, right_extractor, options);
    if (refined.sad < 0.0f) continue;
    float disparity = kl.pt.x - refined.u_right;
    if (disparity < min_d || disparity >= max_d) continue;
    float u_right = refined.u_right;
    if (disparity <= 0.0f) {  // at infinity: ORB-SLAM2 keeps it with a tiny disparity
      disparity = 0.01f;
      u_right = kl.pt.x - disparity;
    }
    result.depth[i] = static_cast<float>(bf / disparity);
    result.u_right[i] = u_right;
    result.right_index[i] = best_j;
    sad_and_index.emplace_back(refined.sad, static_cast<int>(i));
  }

  // Step 4: drop matches whose SAD is far above the median.
  std::sort(sad_and_index.begin(), sad_and_index.end());
  int kept = static_cast<int>(sad_and_index.size());
  if (!sad_and_index.empty()) {
    const float median = sad_and_index[sad_and_index.size() / 2].first;
    const float threshold = static_cast<float>(options.outlier_factor * median);
    for (auto it = sad_and_index.rbegin(); it != sad_and_index.rend() && it->first > threshold;
         ++it) {
      result.u_right[it->second] = -1.0f;
      result.depth[it->second] = -1.0f;
      result.right_index[it->second] = -1;
      --kept;
    }
  }
  result.num_matches = kept;
  return result;
}

}  // namespace moslam::feature
