// Monocular map initialization from two views (ORB-SLAM2's Initializer, Mur-Artal et al. 2015,
// Sec. IV; Mur-Artal & Tardós 2017): a homography H and a fundamental matrix F are estimated by
// RANSAC on the SAME random 8-point sets (normalized DLT / normalized 8-point), each hypothesis is
// scored with the symmetric transfer error under chi-square thresholds, and the model is chosen by
// R_H = S_H / (S_H + S_F) > 0.40 (homography: planar or low-parallax scenes). The winner is
// decomposed (Faugeras' 8 homography hypotheses, or E = K^T F K into 4 solutions) and each
// hypothesis is checked by triangulation (cheirality, reprojection, parallax); the reconstruction
// is accepted only with enough points, enough parallax and a clear winner. Failures are results
// (`ok` false with a reason), never exceptions.
//
// Why not cv::findHomography / cv::findFundamentalMat: they run their own RANSAC and return one
// model each, so the two models cannot be scored on the same sets nor with ORB-SLAM2's scores,
// which the model selection needs. The small linear algebra (SVD) is Eigen's.
//
// Deterministic: the RANSAC sets come from a std::mt19937 seeded with `seed`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "moslam/feature/frame.h"
#include "moslam/geometry/se3.h"

namespace moslam::slam {

struct MonoInitializerOptions {
  double sigma = 1.0;              // pixels: keypoint standard deviation at level 0 (ORB-SLAM2)
  int ransac_iterations = 200;     // ORB-SLAM2: 200
  double homography_ratio = 0.40;  // R_H above this selects the homography (ORB-SLAM2: 0.40)
  double min_parallax_deg = 1.0;   // degrees (ORB-SLAM2: 1.0)
  int min_triangulated = 50;       // points (ORB-SLAM2: 50)
  uint32_t seed = 0;               // RANSAC sets (ORB-SLAM2 seeds its generator with 0)
  bool parallel = false;           // H and F in two threads (ORB-SLAM2 does); same result
  void Check() const;              // InputError naming the field
};

enum class TwoViewModel { kNone, kHomography, kFundamental };
const char* ToString(TwoViewModel model);

struct MonoInitialization {
  bool ok = false;
  std::string reason;  // why not, when !ok
  TwoViewModel model = TwoViewModel::kNone;
  double score_h = 0.0, score_f = 0.0;
  double ratio_h = 0.0;  // S_H / (S_H + S_F)
  int num_inliers = 0;   // of the selected model
  double parallax_deg = 0.0;
  geometry::SE3 T_cam2_cam1;  // unit-norm translation (scale is unobservable)
  // Per correspondence: triangulated with enough parallax, and then its position in camera 1.
  std::vector<bool> triangulated;
  std::vector<Eigen::Vector3d> points_cam1;
  int num_triangulated = 0;
};

// pixels1[i] <-> pixels2[i]: undistorted pixel correspondences; K: the pinhole intrinsics.
// Sizes must agree (CHECK).
MonoInitialization InitializeTwoView(const std::vector<Eigen::Vector2d>& pixels1,
                                     const std::vector<Eigen::Vector2d>& pixels2,
                                     const Eigen::Matrix3d& K,
                                     const MonoInitializerOptions& options = {});

// ORB-SLAM2's ORBmatcher::SearchForInitialization: for each level-0 keypoint of frame1, the
// best level-0 keypoint of frame2 inside a square window of half-size `window` pixels around
// (*prev_matched)[i] (its match position in the previous frame, initially its own position),
// distance <= feature::kThLow and below `ratio` times the second best; each keypoint of frame2
// kept once; orientation-histogram consistency. Returns per keypoint of frame1 the index in
// frame2 or -1, and moves the matched entries of *prev_matched to their new positions.
std::vector<int> SearchForInitialization(const feature::Frame& frame1, const feature::Frame& frame2,
                                         std::vector<Eigen::Vector2f>* prev_matched,
                                         float window = 100.0f, float ratio = 0.9f);

}  // namespace moslam::slam
