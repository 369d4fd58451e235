// ORB feature extraction as in ORB-SLAM2 (Mur-Artal & Tardós 2017) on top of ORB (Rublee et al.
// 2011), with the central change of Sun et al. 2019: a binary movable-object mask enters the
// extractor, and corner candidates on masked pixels are dropped *before* the quadtree
// distribution, so that a frame keeps its full feature budget on the static scene instead of
// losing the keypoints that fell on cars or people.
//
// Per frame: a scale pyramid (level l is the image scaled by 1 / scale_factor^l); FAST-9 corners
// in grid cells with a fallback threshold where a cell is empty; the mask test; per-level quotas
// (a geometric series, like ORB-SLAM2 and OpenCV); quadtree distribution; orientation by
// intensity centroid; steered BRIEF on a Gaussian-smoothed level.
//
//   OrbExtractor extractor(options);
//   OrbFeatures features;
//   extractor.Extract(image, movable_mask, &features);  // mask may be empty
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "moslam/feature/orb_descriptor.h"
#include "moslam/feature/orb_options.h"
#include "moslam/feature/quadtree.h"

namespace moslam::feature {

struct OrbFeatures {
  // In level-0 (input image) pixel coordinates. octave = pyramid level, size = 31 * scale of the
  // level (pixels), angle in degrees [0, 360), response = FAST score. Ordered by level.
  std::vector<cv::KeyPoint> keypoints;
  // keypoints.size() x 32, CV_8U: row i is the 256-bit descriptor of keypoint i.
  cv::Mat descriptors;
};

// Not thread-safe: it keeps per-frame scratch buffers (pyramid, candidates) so that repeated calls
// on images of one size allocate little. Use one extractor per thread (e.g. left and right image).
class OrbExtractor {
 public:
  // Throws InputError when the options are invalid.
  explicit OrbExtractor(const OrbExtractorOptions& options);

  // `image`: CV_8UC1, at least 64x64 pixels. `mask`: empty (no mask) or CV_8UC1 of the image's
  // size, non-zero = movable object; it is grown by options.mask_dilation_px and keypoints whose
  // level-0 position rounds to a masked pixel are never produced. Throws InputError on a wrong
  // image or mask. Returns exactly options.num_features keypoints whenever the unmasked image
  // has enough corners: a level that cannot fill its quota passes the rest to the next finer one.
  // The per-cell FAST threshold is chosen before the mask is applied, as ORB-SLAM2 would choose
  // it, so a mask only removes candidates and never changes the others.
  void Extract(const cv::Mat& image, const cv::Mat& mask, OrbFeatures* features);
  OrbFeatures Extract(const cv::Mat& image, const cv::Mat& mask = cv::Mat());

  const OrbExtractorOptions& options() const { return options_; }
  int num_levels() const { return options_.num_levels; }
  // Scale of level l relative to the input: scale_factor^l. Keypoint coordinates at level l are
  // level-0 coordinates times inv_scale_factors()[l].
  const std::vector<float>& scale_factors() const { return scale_; }
  const std::vector<float>& inv_scale_factors() const { return inv_scale_; }
  // scale^2, the variance (in level-0 pixels^2) ORB-SLAM2 assigns to a keypoint of each level.
  const std::vector<float>& level_sigma2() const { return sigma2_; }
  const std::vector<float>& inv_level_sigma2() const { return inv_sigma2_; }
  // Keypoint quotas per level for num_features (before passing on shortfalls).
  const std::vector<int>& features_per_level() const { return quota_; }
  // The pyramid of the last Extract (for stereo matching in frames): level 0 shares the input
  // image's data; valid until the next Extract. Levels too small to hold a keypoint (fewer than
  // 39 pixels on a side) are empty.
  const cv::Mat& level_image(int level) const { return levels_.at(level).image; }

  // What the mask took away, for a viewer (issue 26): while set, each Extract also finds, level by
  // level, the keypoints the distribution would have kept without the mask (same quota, the
  // masked candidates back in) that lie on masked pixels, in level-0 pixels: masked_keypoints().
  // It costs one more distribution per level, so it stays off (the default) unless someone
  // watches; off, the only trace of it is a flag tested per masked candidate.
  void set_keep_masked(bool keep) { keep_masked_ = keep; }
  bool keep_masked() const { return keep_masked_; }
  // Of the last Extract with keep_masked() and a mask; empty otherwise.
  const std::vector<cv::Point2f>& masked_keypoints() const { return masked_keypoints_; }

 private:
  struct Level {
    cv::Mat image;     // the scaled image
    cv::Mat smoothed;  // Gaussian-smoothed image for the descriptors
    std::vector<Candidate> candidates;
    std::vector<Candidate> selected;  // the distributed keypoints
    std::vector<Candidate> masked;    // candidates the mask removed (keep_masked_ only)
  };

  void CheckInputs(const cv::Mat& image, const cv::Mat& mask) const;
  void BuildPyramid(const cv::Mat& image);
  const cv::Mat& PrepareMask(const cv::Mat& mask);
  // FAST corners of one level, with the cell-wise fallback threshold, minus masked ones.
  void DetectCandidates(int level, const cv::Mat& mask);
  void AppendCorners(int level, int offset_x, int offset_y, const cv::Mat& mask);
  void Describe(OrbFeatures* features);
  // keep_masked_: the keypoints of `level` the mask took away from a quota of `wanted`.
  void CollectMasked(int level, int wanted, const cv::Mat& mask);

  OrbExtractorOptions options_;
  std::vector<float> scale_, inv_scale_, sigma2_, inv_sigma2_;
  std::vector<int> quota_;
  cv::Mat dilation_kernel_;

  std::vector<Level> levels_;
  cv::Mat dilated_mask_;
  std::vector<cv::KeyPoint> fast_;  // cv::FAST output, reused
  std::vector<int> cell_count_;
  QuadtreeDistributor distributor_;
  bool keep_masked_ = false;
  std::vector<cv::Point2f> masked_keypoints_;
  std::vector<Candidate> all_candidates_, all_selected_;  // CollectMasked's scratch
};

}  // namespace moslam::feature
