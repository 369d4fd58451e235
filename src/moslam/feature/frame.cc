#include "moslam/feature/frame.h"

#include <algorithm>
#include <cmath>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::feature {
namespace {

// Fills everything but u_right/depth from a fresh extraction.
Frame BaseFrame(double timestamp, const cv::Mat& image, const cv::Mat& mask,
                OrbExtractor* extractor, const camera::PinholeCamera& camera) {
  MOSLAM_CHECK(extractor != nullptr);
  Frame frame;
  frame.timestamp = timestamp;
  OrbFeatures features;
  extractor->Extract(image, mask, &features);
  frame.keypoints = std::move(features.keypoints);
  frame.descriptors = features.descriptors;
  frame.keypoints_undistorted = frame.keypoints;
  if (camera.HasDistortion()) {
    for (cv::KeyPoint& kp : frame.keypoints_undistorted) {
      const Eigen::Vector2d px = camera.UndistortPixel(Eigen::Vector2d(kp.pt.x, kp.pt.y));
      kp.pt = cv::Point2f(static_cast<float>(px.x()), static_cast<float>(px.y()));
    }
  }
  frame.u_right.assign(frame.keypoints.size(), -1.0f);
  frame.depth.assign(frame.keypoints.size(), -1.0f);
  frame.scale_factors = extractor->scale_factors();
  frame.inv_scale_factors = extractor->inv_scale_factors();
  frame.level_sigma2 = extractor->level_sigma2();
  frame.inv_level_sigma2 = extractor->inv_level_sigma2();
  frame.bounds = ComputeImageBounds(camera, image.size());
  frame.grid = KeypointGrid(frame.bounds, frame.keypoints_undistorted);
  return frame;
}

}  // namespace

std::optional<Eigen::Vector3d> Frame::UnprojectCamera(size_t i,
                                                      const camera::PinholeCamera& cam) const {
  MOSLAM_CHECK_LT(i, size());
  if (!(depth[i] > 0.0f)) return std::nullopt;
  const cv::Point2f& pt = keypoints_undistorted[i].pt;
  return depth[i] * cam.UnprojectPinhole(Eigen::Vector2d(pt.x, pt.y));
}

int Frame::NumWithDepth() const {
  return static_cast<int>(std::count_if(depth.begin(), depth.end(), [](float d) { return d > 0; }));
}

ImageBounds ComputeImageBounds(const camera::PinholeCamera& camera, cv::Size image_size) {
  const float w = static_cast<float>(image_size.width);
  const float h = static_cast<float>(image_size.height);
  if (!camera.HasDistortion()) return ImageBounds{0.0f, w, 0.0f, h};
  auto undistort = [&](float u, float v) { return camera.UndistortPixel(Eigen::Vector2d(u, v)); };
  const Eigen::Vector2d tl = undistort(0, 0), tr = undistort(w, 0);
  const Eigen::Vector2d bl = undistort(0, h), br = undistort(w, h);
  return ImageBounds{
      static_cast<float>(std::min(tl.x(), bl.x())), static_cast<float>(std::max(tr.x(), br.x())),
      static_cast<float>(std::min(tl.y(), tr.y())), static_cast<float>(std::max(bl.y(), br.y()))};
}

Frame MakeMonocularFrame(double timestamp, const cv::Mat& image, const cv::Mat& mask,
                         OrbExtractor* extractor, const camera::PinholeCamera& camera) {
  return BaseFrame(timestamp, image, mask, extractor, camera);
}

Frame MakeRgbdFrame(double timestamp, const cv::Mat& image, const cv::Mat& depth,
                    const cv::Mat& mask, OrbExtractor* extractor,
                    const camera::PinholeCamera& camera, double bf) {
  if (depth.type() != CV_32FC1 || depth.size() != image.size()) {
    ThrowInput("RGB-D frame: depth image must be CV_32FC1 of the image's size {}x{} (got {}x{})",
               image.cols, image.rows, depth.cols, depth.rows);
  }
  if (!(bf > 0.0) || !std::isfinite(bf)) ThrowInput("RGB-D frame: bf must be > 0 (got {})", bf);
  Frame frame = BaseFrame(timestamp, image, mask, extractor, camera);
  frame.bf = bf;
  for (size_t i = 0; i < frame.size(); ++i) {
    const cv::Point2f& pt = frame.keypoints[i].pt;
    const int col = std::clamp(static_cast<int>(std::lround(pt.x)), 0, depth.cols - 1);
    const int row = std::clamp(static_cast<int>(std::lround(pt.y)), 0, depth.rows - 1);
    const float d = depth.at<float>(row, col);
    if (d > 0.0f && std::isfinite(d)) {
      frame.depth[i] = d;
      frame.u_right[i] = frame.keypoints_undistorted[i].pt.x - static_cast<float>(bf / d);
    }
  }
  return frame;
}

Frame MakeStereoFrame(double timestamp, const cv::Mat& left, const cv::Mat& right,
                      const cv::Mat& mask, OrbExtractor* left_extractor,
                      OrbExtractor* right_extractor, const camera::StereoCamera& camera,
                      const StereoMatchOptions& options, const cv::Mat& right_mask) {
  MOSLAM_CHECK(right_extractor != nullptr && right_extractor != left_extractor);
  if (right.size() != left.size()) {
    ThrowInput("stereo frame: right image {}x{} differs from left image {}x{}", right.cols,
               right.rows, left.cols, left.rows);
  }
  Frame frame = BaseFrame(timestamp, left, mask, left_extractor, camera.left());
  frame.bf = camera.bf();
  OrbFeatures right_features;
  right_extractor->Extract(right, right_mask, &right_features);
  OrbFeatures left_features;  // MatchStereo reads keypoints and descriptors only
  left_features.keypoints = frame.keypoints;
  left_features.descriptors = frame.descriptors;
  StereoMatches matches = MatchStereo(left_features, *left_extractor, right_features,
                                      *right_extractor, camera.bf(), camera.left().fx(), options);
  frame.u_right = std::move(matches.u_right);
  frame.depth = std::move(matches.depth);
  return frame;
}

}  // namespace moslam::feature
