// A frame of the tracking front end (ORB-SLAM2's Frame, Mur-Artal & Tardós 2017): ORB keypoints
// (raw and undistorted), descriptors, per-keypoint stereo/RGB-D right coordinate and depth, the
// extractor's scale pyramid, and a grid over the undistorted image for radius search. It knows
// nothing of map points or key frames; those live in later modules and refer to keypoints by
// index.
//
//   OrbExtractor left(options), right(options);
//   Frame f = MakeStereoFrame(t, images.left, images.right, movable_mask, &left, &right, camera);
//   for (size_t i : f.FeaturesInArea(u, v, radius)) ...
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/camera/stereo_camera.h"
#include "moslam/feature/keypoint_grid.h"
#include "moslam/feature/orb_extractor.h"
#include "moslam/feature/stereo_matcher.h"

namespace moslam::feature {

struct Frame {
  double timestamp = 0.0;  // seconds
  // As extracted (distorted image), and after undistortion with the camera (ideal pixels;
  // identical for rectified or distortion-free images). Same order and octaves.
  std::vector<cv::KeyPoint> keypoints;
  std::vector<cv::KeyPoint> keypoints_undistorted;
  cv::Mat descriptors;  // keypoints.size() x 32, CV_8U
  // Per keypoint: column in the (real or, for RGB-D, virtual) right image and depth in metres;
  // -1 when unknown (monocular, no stereo match, invalid depth).
  std::vector<float> u_right;
  std::vector<float> depth;
  // Per keypoint: 1 when it lies within a few pixels of the frame's movable-object mask
  // (KeypointsNearMask in feature/movable_mask.h); such keypoints track existing map points but
  // seed no new ones. Empty: no mask (none is near).
  std::vector<uint8_t> near_movable;
  // Per keypoint: 1 when tracking saw it move against an earlier frame (slam/moving_keypoints.h;
  // set on keyframes). Empty: not judged.
  std::vector<uint8_t> moving;
  bool NearMovable(size_t i) const { return i < near_movable.size() && near_movable[i] != 0; }
  // Keypoints that may track existing map points but seed no new one.
  bool SeedsNoPoint(size_t i) const {
    return NearMovable(i) || (i < moving.size() && moving[i] != 0);
  }
  // The extractor's pyramid: scale_factors[l] = scale_factor^l, level_sigma2[l] its square.
  std::vector<float> scale_factors;
  std::vector<float> inv_scale_factors;
  std::vector<float> level_sigma2;
  std::vector<float> inv_level_sigma2;
  double bf = 0.0;  // baseline * fx (pixel-metres); 0 for monocular frames
  ImageBounds bounds;
  KeypointGrid grid;

  size_t size() const { return keypoints.size(); }
  int num_levels() const { return static_cast<int>(scale_factors.size()); }
  const uint8_t* descriptor(size_t i) const {
    return descriptors.ptr<uint8_t>(static_cast<int>(i));
  }
  // See KeypointGrid::FeaturesInArea; positions are undistorted pixels.
  std::vector<size_t> FeaturesInArea(float x, float y, float r, int min_level = 0,
                                     int max_level = -1) const {
    return grid.FeaturesInArea(keypoints_undistorted, x, y, r, min_level, max_level);
  }
  // Camera-frame point of keypoint i from its depth; nullopt when the depth is unknown.
  std::optional<Eigen::Vector3d> UnprojectCamera(size_t i, const camera::PinholeCamera& cam) const;
  // Number of keypoints with a depth.
  int NumWithDepth() const;
};

// ORB-SLAM2's image bounds: the undistorted image corners (the image itself when the camera has
// no distortion).
ImageBounds ComputeImageBounds(const camera::PinholeCamera& camera, cv::Size image_size);

// `mask`: movable-object mask for the extractor (empty: none). The extractor must outlive the
// call only. Images as OrbExtractor::Extract requires (throws InputError otherwise).
Frame MakeMonocularFrame(double timestamp, const cv::Mat& image, const cv::Mat& mask,
                         OrbExtractor* extractor, const camera::PinholeCamera& camera);

// `depth`: CV_32FC1 metres of the image's size (0 or non-finite = invalid; InputError otherwise),
// registered to the image. Depth is read at the raw keypoint; u_right = u_undistorted - bf/depth
// (ORB-SLAM2's virtual right coordinate; bf > 0 from the settings' Camera.bf).
Frame MakeRgbdFrame(double timestamp, const cv::Mat& image, const cv::Mat& depth,
                    const cv::Mat& mask, OrbExtractor* extractor,
                    const camera::PinholeCamera& camera, double bf);

// Rectified stereo pair: the left image uses `mask`, the right one `right_mask` (may be empty).
// Two extractors because the matcher reads both pyramids.
Frame MakeStereoFrame(double timestamp, const cv::Mat& left, const cv::Mat& right,
                      const cv::Mat& mask, OrbExtractor* left_extractor,
                      OrbExtractor* right_extractor, const camera::StereoCamera& camera,
                      const StereoMatchOptions& options = {},
                      const cv::Mat& right_mask = cv::Mat());

}  // namespace moslam::feature
