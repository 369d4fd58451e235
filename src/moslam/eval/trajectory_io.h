// Trajectory files: TUM RGB-D, KITTI odometry and EuRoC ground truth.
//
//   TUM    `t tx ty tz qx qy qz qw` a line (seconds; quaternion x-y-z-w); '#' comments and blank
//          lines are skipped; commas count as separators, as in TUM's associate.py.
//   KITTI  12 numbers a line: the top 3x4 of T_world_cam, row-major; no timestamps (a separate
//          times.txt gives them, see ReadTimes). Rotations are re-orthonormalized into the SE3
//          poses; the matrices as read are kept in Trajectory::raw_rotations.
//   EuRoC  csv `#timestamp,p_RS_R_x,p_RS_R_y,p_RS_R_z,q_RS_w,q_RS_x,q_RS_y,q_RS_z,...`: stamps in
//          nanoseconds, quaternion w first; columns after the eighth (velocities, biases) ignored.
//
// Rules shared by the readers, each violation an InputError naming file and line:
//   - wrong field count, a field that is not a number, a zero-length or infinite quaternion;
//   - a timestamp earlier than the previous one (files of real systems are sorted; a shuffled
//     file is more likely a mistake than something to sort silently).
// Tolerated, with a logged warning, because the TUM tools tolerate them:
//   - a repeated timestamp (TUM's fr2/desk ground truth repeats 1311868229.5760): both poses are
//     kept; the TUM convention then uses the later (its scripts read into a dict), the evo one the
//     earlier (numpy's argmin returns the first minimum);
//   - TUM/EuRoC lines with a NaN, and poses whose quaternion is exactly 0 0 0 0: skipped, as TUM's
//     evaluate_rpe.py does. (KITTI poses are matched by index, so a NaN there is an error.)
#pragma once

#include <string>
#include <vector>

#include "moslam/eval/trajectory.h"

namespace moslam::eval {

enum class TrajectoryFormat { kAuto, kTum, kKitti, kEuroc };

// "auto", "tum", "kitti", "euroc" (case-insensitive); InputError otherwise.
TrajectoryFormat ParseTrajectoryFormat(const std::string& name);
const char* TrajectoryFormatName(TrajectoryFormat format);

// Decides from the file itself: a ".csv" name, an EuRoC header ("#timestamp" naming p_RS_R_x) or a
// comma-separated first data line mean EuRoC; otherwise 8 fields mean TUM and 12 KITTI.
// InputError naming the file and line when none fits.
TrajectoryFormat DetectTrajectoryFormat(const std::string& path);

// Reads `path`; kAuto detects the format first. Trajectory::name is set to `path`.
Trajectory ReadTrajectory(const std::string& path,
                          TrajectoryFormat format = TrajectoryFormat::kAuto);
Trajectory ReadTum(const std::string& path);
Trajectory ReadKitti(const std::string& path);
Trajectory ReadEuroc(const std::string& path);

// A KITTI times.txt: one timestamp (seconds) a line, non-decreasing.
std::vector<double> ReadTimes(const std::string& path);
// Gives `trajectory` the stamps read from `times_path`; their count must equal the pose count.
void AttachTimes(const std::string& times_path, Trajectory* trajectory);

// Writers; numbers are written in the shortest form that reads back to the same double, so a
// write/read round trip keeps stamps and positions exactly and rotations up to the rounding of
// renormalizing the quaternion (EuRoC stamps: up to their nanosecond rounding). WriteTum and
// WriteEuroc need timestamps (InputError otherwise). WriteKitti writes the raw rotations when the
// trajectory has them.
void WriteTum(const Trajectory& trajectory, const std::string& path);
void WriteKitti(const Trajectory& trajectory, const std::string& path);
void WriteEuroc(const Trajectory& trajectory, const std::string& path);

}  // namespace moslam::eval
