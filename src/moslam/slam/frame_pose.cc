#include "moslam/slam/frame_pose.h"

#include "moslam/util/check.h"

namespace moslam::slam {

std::vector<optim::Observation> FrameObservations(const feature::Frame& frame,
                                                  const std::vector<size_t>& indices,
                                                  const optim::FarStereoWeighting& far) {
  std::vector<optim::Observation> observations;
  observations.reserve(indices.size());
  for (size_t i : indices) {
    const cv::KeyPoint& kp = frame.keypoints_undistorted[i];
    optim::Observation obs;
    obs.pixel = Eigen::Vector2d(kp.pt.x, kp.pt.y);
    obs.u_right = frame.u_right[i];
    obs.inv_sigma2 = frame.inv_level_sigma2[kp.octave];
    observations.push_back(obs);
  }
  far.ApplyToAll(frame.bf, 1, observations,
                 [](optim::Observation& o) -> optim::Observation& { return o; });
  return observations;
}

optim::PoseOptimizerResult OptimizeFramePose(const optim::CameraModel& camera,
                                             const feature::Frame& frame,
                                             const std::vector<size_t>& indices,
                                             const std::vector<Eigen::Vector3d>& points_world,
                                             const geometry::SE3& T_cam_world_init, int num_threads,
                                             const std::vector<double>& weights,
                                             const std::vector<bool>& initial_outlier) {
  MOSLAM_CHECK(indices.size() == points_world.size());
  optim::PoseOptimizerOptions options;
  options.num_threads = num_threads;
  return optim::OptimizePose(camera, T_cam_world_init, points_world,
                             FrameObservations(frame, indices), options, initial_outlier, weights);
}

}  // namespace moslam::slam
