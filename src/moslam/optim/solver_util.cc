#include "moslam/optim/solver_util.h"

#include <cmath>
#include <mutex>

#include <glog/logging.h>

#include "moslam/util/check.h"

namespace moslam::optim {

void QuietCeresLogging() {
  static std::once_flag once;
  std::call_once(once, [] {
    // Ceres logs through glog even with logging_type = SILENT (e.g. "Linear solver failure" when a
    // Levenberg-Marquardt step is rejected, which is routine). Keep errors, drop the rest; a
    // higher level set by the application is kept.
    if (FLAGS_minloglevel < google::GLOG_ERROR) FLAGS_minloglevel = google::GLOG_ERROR;
  });
}

ceres::Solver::Options QuietSolverOptions(int max_iterations, int num_threads) {
  QuietCeresLogging();
  ceres::Solver::Options options;
  options.max_num_iterations = max_iterations;
  options.num_threads = num_threads;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  return options;
}

ceres::Problem::Options BorrowingProblemOptions() {
  ceres::Problem::Options options;
  options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  return options;
}

void CheckCamera(const CameraModel& camera) {
  MOSLAM_CHECK(camera.fx > 0.0 && camera.fy > 0.0 && std::isfinite(camera.cx) &&
               std::isfinite(camera.cy) && camera.bf >= 0.0)
      << "camera model fx " << camera.fx << " fy " << camera.fy << " cx " << camera.cx << " cy "
      << camera.cy << " bf " << camera.bf;
}

void CheckObservation(const CameraModel& camera, const Observation& observation) {
  MOSLAM_CHECK(observation.inv_sigma2 > 0.0 && std::isfinite(observation.inv_sigma2))
      << "observation inv_sigma2 " << observation.inv_sigma2;
  MOSLAM_CHECK(observation.right_info_scale > 0.0 && observation.right_info_scale <= 1.0)
      << "observation right_info_scale " << observation.right_info_scale;
  MOSLAM_CHECK(!observation.is_stereo() || camera.bf > 0.0)
      << "stereo observation with a monocular camera (bf = 0)";
}

void CheckCameraAndObservations(const CameraModel& camera,
                                const std::vector<Observation>& observations) {
  CheckCamera(camera);
  for (const Observation& observation : observations) CheckObservation(camera, observation);
}

}  // namespace moslam::optim
