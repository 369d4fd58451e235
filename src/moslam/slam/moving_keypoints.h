// Keypoints seen moving (issue 24, "geometry for what no network knows"): before a keyframe's
// keypoints become map points, each one with a depth is lifted to 3D, moved into a frame a few
// frames earlier with the two tracked poses, and looked for there. A static keypoint is found
// again where it projects (within a few pixels; FAST re-detects it); one on a walking body is
// found displaced by the body's motion (a person crossing at 1.4 m/s, 2 m away, moves ~12 px per
// frame at 30 frames/s), or at another depth. Such keypoints seed no map point, whatever the
// mask says: this is what keeps the parts of bodies a network misses out of the map, and it
// needs no network at all (an unknown mover). It is the two-view reprojection residual that
// CFP-SLAM and DynaSLAM's geometric check use, applied where points are made rather than after.
//
// A keypoint with no match in the earlier frame is not judged (not re-detected, or newly seen).
#pragma once

#include <cstdint>
#include <vector>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/feature/frame.h"
#include "moslam/geometry/se3.h"

namespace moslam::slam {

struct MovingKeypointsOptions {
  bool enabled = true;
  int frame_gap = 3;  // the earlier frame is this many tracked frames back (>= 1)
  // A match within static_radius (pixels at level 0, x the level's scale) of the projection
  // makes the keypoint static; a distinct match only farther, up to search_radius, moving.
  float static_radius = 3.0f;
  float search_radius = 40.0f;
  int max_distance = 50;  // descriptor distance of a match (ORB-SLAM2's TH_LOW)
  // The static match's depth must agree with the projected depth: |d - z| <= abs + rel * z.
  double depth_abs = 0.05;
  double depth_rel = 0.03;
  void Check() const;  // InputError naming the field
};

// Per keypoint of `current`: 1 when seen moving against `earlier`; 0 when static, unjudged, or
// without depth. Poses are T_cam_world of each frame.
std::vector<uint8_t> FindMovingKeypoints(const feature::Frame& current,
                                         const geometry::SE3& T_current_world,
                                         const feature::Frame& earlier,
                                         const geometry::SE3& T_earlier_world,
                                         const camera::PinholeCamera& camera,
                                         const MovingKeypointsOptions& options);

}  // namespace moslam::slam
