// What the optimizers see of the map: a camera model and observations of 3D points, as plain
// data. The optim module knows nothing of KeyFrame/MapPoint; the slam module copies what it needs
// into these structs and writes the results back, so the problems can be built and tested alone.
#pragma once

#include <cstddef>

#include <Eigen/Core>

namespace moslam::optim {

// Ideal pinhole (undistorted pixels, as feature::Frame::keypoints_undistorted) plus the stereo
// term: a point at depth Z has u_right = u - bf / Z (ORB-SLAM2's stereo/RGB-D observation).
struct CameraModel {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;  // pixels
  double bf = 0.0;                                // baseline * fx (pixel-metres); 0 = monocular
};

// One observation of a point in a camera. `u_right < 0` makes it a monocular (2D) residual,
// otherwise a stereo (3D) residual [u, v, u_right]. The residual is whitened by
// sqrt(inv_sigma2) (ORB-SLAM2: 1 / scale_factor^(2*octave), the keypoint's pyramid level).
struct Observation {
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // undistorted pixel (u, v)
  double u_right = -1.0;                            // pixels; < 0: monocular
  double inv_sigma2 = 1.0;                          // 1 / pixel variance (> 0)
  // Multiplies inv_sigma2 for the u_right row only, in (0, 1]: a stereo depth less certain than
  // the pixel's position (far points, issue 29; slam::LocalMapperOptions::far_stereo).
  double right_info_scale = 1.0;

  bool is_stereo() const { return u_right >= 0.0; }
};

// ORB-SLAM2's chi-square thresholds at 95 %: 2 DoF (monocular) and 3 DoF (stereo).
inline constexpr double kChi2Mono = 5.991;
inline constexpr double kChi2Stereo = 7.815;

// How an optimization weighs the u_right row of a stereo/RGB-D observation whose stereo depth
// z = bf / (u - u_right) lies beyond the close depth (ThDepth baselines: ORB-SLAM2's "far"
// keypoints, Mur-Artal & Tardos 2017, Sec. III-A, which carry little scale information: a
// disparity error of a fixed size is a depth error growing with z^2).
//  kFull (ORB-SLAM2): as every other row.
//  kDepthWeighted: its information scaled by (close_depth / z)^2, i.e. the disparity's standard
//    deviation taken as growing in proportion to z past close_depth, where close points can hold
//    the scale instead: fully when the problem has at least kCloseObservationsPerPose close
//    stereo observations per pose (ORB-SLAM2 wants 100 close points in a keyframe), not at all
//    under kCloseObservationsPerPoseNone (half of that), blended linearly between: on an open
//    road (synthetic open_road: 23-26 close matches a frame) the far disparities are the only
//    scale there is; a street (KITTI 06: median 102, 10 % of frames under 67) has near points. On
//    real stereo (KITTI 06) the disparities of points 20-45 m away are biased by -0.15 to -0.23 px
//    against depths triangulated from ground-truth poses, where synthetic pairs show under 0.03 px:
//    an error that does not average out over points, and through z = bf / d a trajectory 0.2-0.3 %
//    too long (issue 29; docs/EVALUATION.md "Stereo disparity bias").
//  kMonocular: dropped, only [u, v] enter.
enum class FarStereo { kFull, kDepthWeighted, kMonocular };

struct FarStereoWeighting {
  static constexpr double kCloseObservationsPerPose = 100.0;
  static constexpr double kCloseObservationsPerPoseNone = 50.0;
  FarStereo policy = FarStereo::kFull;
  double close_depth = 0.0;  // metres (settings.CloseDepthMetres()); <= 0: every depth is close

  // Whether `observation` is stereo with a depth in (0, close_depth].
  bool IsClose(double bf, const Observation& observation) const;
  // kDepthWeighted's strength in [0, 1] for a problem with `close` close stereo observations
  // over `poses` poses: 0 up to kCloseObservationsPerPoseNone per pose, 1 from
  // kCloseObservationsPerPose, linear between.
  static double Strength(size_t close, size_t poses);
  // Applies the policy to `observation` (nothing for a monocular one or one within close_depth);
  // kDepthWeighted scales the information by max((close_depth / z)^2, 1 - strength).
  void Apply(double bf, double strength, Observation* observation) const;
  // Apply to the observation get(item) of every item, with the strength of their close stereo
  // observations over `poses` poses (one problem: a frame's matches, a bundle's edges).
  template <class Items, class Get>
  void ApplyToAll(double bf, size_t poses, Items& items, Get get) const {
    if (policy == FarStereo::kFull) return;
    size_t close = 0;
    for (auto& item : items) close += IsClose(bf, get(item));
    const double strength = Strength(close, poses);
    for (auto& item : items) Apply(bf, strength, &get(item));
  }
};

}  // namespace moslam::optim
