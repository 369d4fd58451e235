#include "moslam/slam/frame_pose.h"

#include <random>

#include <gtest/gtest.h>

namespace moslam::slam {
namespace {

struct Scene {
  optim::CameraModel camera{718.856, 718.856, 607.19, 185.22, 386.14};  // KITTI 04-12
  feature::Frame frame;
  std::vector<size_t> indices;
  std::vector<Eigen::Vector3d> points;
  std::vector<bool> corrupted;
};

// Points in front of a camera at T_cam_world; keypoints at their exact projections (stereo for
// every other one), except `num_outliers` moved by 30 px.
Scene MakeScene(const geometry::SE3& T_cam_world, int n, int num_outliers) {
  Scene s;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> xy(-8.0, 8.0), z(4.0, 30.0);
  s.frame.scale_factors = {1.0f, 1.2f};
  s.frame.inv_level_sigma2 = {1.0f, 1.0f / 1.44f};
  s.frame.level_sigma2 = {1.0f, 1.44f};
  const geometry::SE3 T_world_cam = T_cam_world.Inverse();
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d pc(xy(rng), 0.3 * xy(rng), z(rng));
    const Eigen::Vector3d pw = T_world_cam * pc;
    double u = s.camera.fx * pc.x() / pc.z() + s.camera.cx;
    const double v = s.camera.fy * pc.y() / pc.z() + s.camera.cy;
    float ur = k % 2 == 0 ? static_cast<float>(u - s.camera.bf / pc.z()) : -1.0f;
    const bool outlier = k < num_outliers;
    if (outlier) {
      u += 30.0;
      if (ur >= 0.0f) ur += 30.0f;
    }
    cv::KeyPoint kp(static_cast<float>(u), static_cast<float>(v), 31.0f, 0.0f, 0.0f, k % 2);
    s.frame.keypoints.push_back(kp);
    s.frame.keypoints_undistorted.push_back(kp);
    s.frame.u_right.push_back(ur);
    s.frame.depth.push_back(ur >= 0.0f ? static_cast<float>(pc.z()) : -1.0f);
    s.indices.push_back(static_cast<size_t>(k));
    s.points.push_back(pw);
    s.corrupted.push_back(outlier);
  }
  return s;
}

TEST(OptimizeFramePose, RecoversPoseAndFlagsOutliers) {
  geometry::Vector6d xi;
  xi << 0.3, -0.1, 2.0, 0.02, -0.05, 0.01;
  const geometry::SE3 truth = geometry::SE3::Exp(xi);
  const Scene s = MakeScene(truth, 200, 20);
  geometry::Vector6d delta;
  delta << 0.05, -0.03, 0.1, 0.01, 0.005, -0.01;
  const auto result =
      OptimizeFramePose(s.camera, s.frame, s.indices, s.points, geometry::SE3::Exp(delta) * truth);
  EXPECT_LT((result.T_cam_world.translation() - truth.translation()).norm(), 1e-4);
  EXPECT_LT(result.T_cam_world.rotation().angularDistance(truth.rotation()), 1e-5);
  ASSERT_EQ(result.inlier.size(), s.indices.size());
  for (size_t k = 0; k < s.indices.size(); ++k) {
    EXPECT_EQ(result.inlier[k], !s.corrupted[k]) << "observation " << k;
  }
  EXPECT_EQ(result.num_inliers, 180);
}

TEST(OptimizeFramePose, TooFewMatchesIsNotAnError) {
  const Scene s = MakeScene(geometry::SE3::Identity(), 2, 0);
  const auto result =
      OptimizeFramePose(s.camera, s.frame, s.indices, s.points, geometry::SE3::Identity());
  EXPECT_EQ(result.num_inliers, 0);
}

}  // namespace
}  // namespace moslam::slam
