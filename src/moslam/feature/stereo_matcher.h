// Sparse stereo matching of ORB keypoints between rectified images, following ORB-SLAM2's
// Frame::ComputeStereoMatches (Mur-Artal & Tardós 2017, Sec. III-A):
//   1. right keypoints are indexed by image row, each over a band of +-2 * scale of its level;
//   2. a left keypoint's candidates are right keypoints in its row band, within one pyramid level,
//      with disparity in [0, bf / min_depth]; the best ORB descriptor distance must be below a
//      threshold;
//   3. the match is refined by sum of absolute differences (SAD) of an 11 x 11 patch on the
//      keypoint's pyramid level over +-5 pixels, then to sub-pixel by a parabola through the
//      three SAD values around the minimum (rejected when the vertex is more than 1 px away);
//      Issue 29 changed the defaults: the sub-pixel step runs on level 0 (refine_at_level0) and
//      fits two lines instead of a parabola (SubPixelFit), which removed a disparity bias;
//   4. matches whose SAD exceeds 1.5 * 1.4 * median SAD are discarded as outliers.
// Depth = bf / disparity.
#pragma once

#include <vector>

#include "moslam/feature/orb_extractor.h"

namespace moslam::feature {

// How the SAD minimum is refined to sub-pixel (step 3 of the header).
enum class SubPixelFit {
  // ORB-SLAM2's parabola through the three SADs around the minimum. SAD is V-shaped near its
  // minimum (|delta| * sum of |gradient|), so the parabola's vertex is pulled toward the integer:
  // a true offset delta in (-0.5, 0.5) is estimated as delta / (2 (1 - |delta|)).
  kParabola,
  // Equiangular line fit (Shimizu & Okutomi 2001, "Significance and attributes of sub-pixel
  // estimation on area-based matching"): two lines of opposite slope through the three SADs, exact
  // for a V-shaped cost and symmetric, so no pull toward integer disparities.
  kEquiangular,
};

struct StereoMatchOptions {
  // Largest Hamming distance (bits of 256) of a descriptor match. ORB-SLAM2 uses
  // (TH_HIGH + TH_LOW) / 2 = 75.
  int max_descriptor_distance = 75;
  // Half-height of a right keypoint's row band, in multiples of its level's scale (> 0).
  float row_band_scale = 2.0f;
  // Half-size of the SAD patch in pixels of the keypoint's level (>= 1; 5 -> 11 x 11).
  int patch_half_size = 5;
  // SAD search half-width in pixels of the keypoint's level (>= 1).
  int search_half_width = 5;
  // Nearest depth accepted, in baselines (> 0): max disparity = bf / (this * baseline) = fx / this.
  double min_depth_baselines = 1.0;
  // Matches with SAD > outlier_factor * median SAD are dropped (> 0; ORB-SLAM2: 1.5 * 1.4).
  double outlier_factor = 1.5 * 1.4;
  // Sub-pixel step (issue 29: the parabola biases disparities; see SubPixelFit).
  SubPixelFit subpixel = SubPixelFit::kEquiangular;
  // Refine the match on level 0 (full resolution) after the SAD search on the keypoint's level:
  // SAD over a window of patch_half_size * scale level-0 pixels, searched over +-(scale + 1)
  // pixels around the level's minimum, then the sub-pixel fit. On the keypoint's level alone
  // (ORB-SLAM2) the sub-pixel error is in that level's pixels, up to 3.6 level-0 px on level 7.
  bool refine_at_level0 = true;
  // Largest half-size of the level-0 window (>= 1). Larger windows on a strongly slanted surface
  // (the road 5-10 m ahead: 0.33 px more disparity per row) mix rows of different disparity and
  // weigh them by their texture: measured on kitti_cars, half-size 12 (octave 5) has a +0.05 px
  // bias there, 8 has +0.03 px at the same spread.
  int level0_max_half_size = 8;
  // Ambiguity test on the keypoint's level: the match is dropped when its SAD is above this
  // fraction of the smallest SAD at least two pixels away from it (in [0, 1]; 1 keeps all, as
  // ORB-SLAM2). Repeated texture along the row gives a second minimum as deep as the first.
  double max_sad_ratio = 1.0;

  // Throws InputError naming the option.
  void Check() const;
};

struct StereoMatches {
  // One entry per left keypoint; -1 where no (inlier) match was found.
  std::vector<float> u_right;    // sub-pixel column in the right image (level-0 pixels)
  std::vector<float> depth;      // metres
  std::vector<int> right_index;  // index of the matched right keypoint
  int num_matches = 0;
};

// `left`/`right` come from the last Extract calls of `left_extractor`/`right_extractor` (their
// pyramids are read for the SAD step), on rectified images of one size. bf (pixel-metres) and
// fx (pixels) must be > 0 (CHECK). Throws InputError when options.Check() does.
StereoMatches MatchStereo(const OrbFeatures& left, const OrbExtractor& left_extractor,
                          const OrbFeatures& right, const OrbExtractor& right_extractor, double bf,
                          double fx, const StereoMatchOptions& options = {});

}  // namespace moslam::feature
