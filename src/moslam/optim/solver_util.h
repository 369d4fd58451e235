// Ceres settings shared by the optimizers of this module.
#pragma once

#include <vector>

#include <ceres/ceres.h>

#include "moslam/optim/observation.h"

namespace moslam::optim {

// Raises glog's minimum level to ERROR once per process (Ceres's warnings about rejected steps
// are routine and would flood stderr every frame). Called by QuietSolverOptions.
void QuietCeresLogging();

// Solver options that print nothing (no progress, no glog output below ERROR) and stop after
// `max_iterations` Levenberg-Marquardt iterations.
ceres::Solver::Options QuietSolverOptions(int max_iterations, int num_threads);

// A Problem that borrows cost functions, loss functions and manifolds: the optimizers own them so
// that they can be reused across the problems of several rounds or stages.
ceres::Problem::Options BorrowingProblemOptions();

// Camera intrinsics and observations must be usable (broken invariant otherwise: the slam module
// fills them from checked settings): focal lengths > 0, inv_sigma2 > 0, and bf > 0 when any
// observation is stereo.
void CheckCameraAndObservations(const CameraModel& camera,
                                const std::vector<Observation>& observations);
void CheckCamera(const CameraModel& camera);
void CheckObservation(const CameraModel& camera, const Observation& observation);

}  // namespace moslam::optim
