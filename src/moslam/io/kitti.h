// KITTI odometry sequences (Geiger et al., CVPR 2012; devkit readme of the odometry benchmark):
// a folder with times.txt (one stamp in seconds a line), calib.txt (3x4 projection matrices
// P0..P3 of the rectified cameras, row-major) and image_0/ (left grey), image_1/ (right grey),
// image_2/, image_3/ (left and right colour) holding 000000.png, 000001.png, ...
//
// A missing right-camera folder makes the sequence monocular; it is not an error.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "moslam/geometry/so3.h"
#include "moslam/io/sequence.h"

namespace moslam::io {

struct KittiOptions {
  // Use the colour pair image_2/ + image_3/ (and P2, P3) instead of the grey image_0/ + image_1/.
  bool colour = false;
  // Use only the left camera even when the right camera's images are present.
  bool monocular = false;
  // Ground-truth poses file; empty: <folder>/poses.txt when it exists. A given path must exist.
  std::string poses_path;
};

// The projection matrices of calib.txt; P[i] is absent when the file has no line for camera i.
struct KittiCalibration {
  std::array<std::optional<geometry::Matrix3x4d>, 4> P;
};

// Accepts "P0: v1 .. v12" lines and, as in some copies of the data, the same lines without the
// "Pi:" labels (then the i-th line is P_i). Lines labelled Tr... (velodyne/IMU extrinsics) and
// R0_rect are ignored. Throws InputError naming file and line for a wrong number of values,
// a non-number, a repeated or unknown label, or labelled and unlabelled lines mixed.
KittiCalibration ReadKittiCalibration(const std::string& path);

// The pinhole intrinsics of a rectified camera from its projection matrix (no distortion; image
// size unknown). Throws InputError when P is not of the form K [I | t] with fx, fy > 0.
camera::PinholeOptions IntrinsicsFromProjection(const geometry::Matrix3x4d& P);

// bf (baseline times fx, pixel-metres) of the rectified pair (left, right):
// bf = -(right(0,3) - left(0,3)), since P(0,3) = -fx * (camera's x offset from camera 0).
// Throws InputError unless the two share intrinsics and the right camera is to the right.
double StereoBfFromProjections(const geometry::Matrix3x4d& left, const geometry::Matrix3x4d& right);

// A stereo (or, without the right images, monocular) sequence with its calibration: the left
// camera's intrinsics (size from the first left image) and bf. Throws InputError for a missing
// folder, times.txt or calib.txt, a malformed or non-increasing time stamp, or an image that a
// time stamp implies but that does not exist (naming times.txt, the line and the image).
Sequence ReadKitti(const std::string& folder, const KittiOptions& options = {});

}  // namespace moslam::io
