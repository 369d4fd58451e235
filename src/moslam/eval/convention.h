// The two conventions of trajectory evaluation in the field, which give different numbers on the
// same files:
//   kTum  the TUM RGB-D benchmark scripts (J. Sturm et al., "A benchmark for the evaluation of
//         RGB-D SLAM systems", IROS 2012): associate.py / evaluate_ate.py / evaluate_rpe.py.
//   kEvo  evo (M. Grupp, github.com/MichaelGrupp/evo, checked against 1.36): evo_ape / evo_rpe.
// Which rules reproduce which published number is listed in REFERENCE.md and tested in
// reference_test.cc.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "moslam/eval/association.h"
#include "moslam/eval/trajectory.h"

namespace moslam::eval {

enum class Convention { kTum, kEvo };

// "tum" or "evo"; InputError otherwise.
Convention ParseConvention(const std::string& name);
const char* ConventionName(Convention convention);

// The tools' default association windows: 0.02 s (associate.py), 0.01 s (evo).
double DefaultMaxDt(Convention convention);

// Associates per convention: AssociateGreedy (tum) or AssociateNearest (evo) when both have
// timestamps, AssociateByIndex when neither has. InputError when only one of them has stamps.
Association AssociatePoses(const Trajectory& gt, const Trajectory& est, Convention convention,
                           double max_dt, double offset);

// Throws InputError unless both trajectories have timestamps or neither has.
void RequireComparableStamps(const Trajectory& gt, const Trajectory& est);

// Rotation angle (radians) of the rotation block of a pose matrix, as both tools compute it:
// arccos((trace(R) - 1) / 2) with the argument clamped to [-1, 1] (TUM compute_angle, evo so3_log).
double RotationAngleOfMatrix(const Eigen::Matrix3d& R);

// Inverse of a pose matrix the way evo's se3_inverse computes it, [R^T, -R^T t], which differs
// from the true inverse for the not quite orthonormal rotations of KITTI files.
Eigen::Matrix4d InverseAsEvo(const Eigen::Matrix4d& T);

// The compared poses, for plots: one time (stamp or index) and two positions per pair.
struct ComparedPoses {
  std::vector<double> times;
  std::vector<Eigen::Vector3d> gt_positions;
  std::vector<Eigen::Vector3d> est_positions;
};
// The positions of associated trajectories (pose k with pose k), times from the ground truth.
ComparedPoses MakeComparedPoses(const Trajectory& gt, const Trajectory& est);

}  // namespace moslam::eval
