// Relocalization of a lost frame against the map (ORB-SLAM2's Tracking::Relocalization,
// Mur-Artal & Tardós 2017): keyframes that look like the frame come from the keyframe database
// (bag of words); for each, the frame is matched to the keyframe's map points through the
// direct index (SearchByBoW, >= 15 matches), a pose is found with PnP RANSAC, refined with
// pose-only optimization, and, when fewer than 50 inliers remain, more of the keyframe's points
// are found by projection (radius 10, then 3 pixels) and the pose optimized again. The first
// candidate with >= 50 inliers gives the frame its pose and its map points.
//
// Differences from ORB-SLAM2, on purpose: candidates are tried one after the other with a full
// RANSAC each (OpenCV's solvePnPRansac), in the database's order (best accumulated score first),
// where ORB-SLAM2 interleaves 5 RANSAC iterations per candidate; the result is the same pose
// whenever one candidate is good, and the order makes runs repeatable.
//
// With a prior (a short loss, slam/tracker_recovery.cc) a candidate's pose must also put the
// camera within the prior's radius of where the motion model predicts it; one that does not is
// refused and the next candidate tried. On a street of identical houses the best-scoring
// keyframe after a short loss is often a look-alike tens of metres away (docs/EVALUATION.md,
// street_repeat_loop); a camera cannot get there in a second.
//
// The caller holds Map::mutex() (keyframes' points are read); the frame's BoW is computed
// beforehand (KeyFrameDatabase::ComputeBow needs no lock).
#pragma once

#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "moslam/feature/frame.h"
#include "moslam/geometry/se3.h"
#include "moslam/map/keyframe.h"
#include "moslam/map/map_point.h"
#include "moslam/optim/observation.h"
#include "moslam/slam/bow_matcher.h"
#include "moslam/slam/keyframe_database.h"
#include "moslam/slam/pnp_ransac.h"

namespace moslam::slam {

struct RelocalizerOptions {
  int min_bow_matches = 15;        // a candidate needs this many BoW matches (ORB-SLAM2: 15)
  int min_optimized_inliers = 10;  // after the first pose optimization (ORB-SLAM2: 10)
  int min_inliers = 50;            // to accept the pose (ORB-SLAM2: 50)
  // Projection searches with the candidate's remaining points: radius at level 0 (pixels) and
  // accepted descriptor distance; the second runs when 30 < inliers < 50 (ORB-SLAM2: 10/100,
  // then 3/64).
  float wide_radius = 10.0f;
  int wide_max_distance = 100;
  float narrow_radius = 3.0f;
  int narrow_max_distance = 64;
  BowMatchOptions bow;  // ratio 0.75 (ORB-SLAM2's ORBmatcher(0.75, true))
  PnpRansacOptions pnp;
  int num_threads = 1;  // pose optimizer
  void Check() const;   // InputError naming the field
};

// Where the camera can be after a short loss.
struct RelocalizationPrior {
  Eigen::Vector3d camera_center = Eigen::Vector3d::Zero();  // predicted, world frame
  double radius = 0.0;                                      // map units (metres but monocular)
};

struct RelocalizationResult {
  bool success = false;
  geometry::SE3 T_cam_world;
  // Per keypoint of the frame: the map point it was matched to (inliers only), when success.
  std::vector<std::shared_ptr<map::MapPoint>> points;
  int num_inliers = 0;
  int num_candidates = 0;                   // keyframes the database proposed
  std::shared_ptr<map::KeyFrame> keyframe;  // the candidate that gave the pose
  // Candidates whose pose the prior refused, and the nearest of them (distance from the
  // predicted camera centre; infinity when none).
  int refused_by_prior = 0;
  double nearest_refused = std::numeric_limits<double>::infinity();
};

RelocalizationResult Relocalize(const KeyFrameDatabase& database, const feature::Frame& frame,
                                const KeyFrameBow& frame_bow, const optim::CameraModel& camera,
                                const RelocalizerOptions& options = {},
                                const std::optional<RelocalizationPrior>& prior = std::nullopt);

// ORB-SLAM2's SearchByProjection(Frame, KeyFrame, already found, th, ORBdist): projects the
// keyframe's points that are not in `points` yet with `T_cam_world`, and matches each to the
// closest free keypoint (descriptor distance <= max_distance) within radius x the predicted
// level's scale on levels predicted +- 1, keeping rotation-consistent matches. Adds them to
// `points` (per keypoint) and returns how many.
int SearchKeyFrameByProjection(const map::KeyFrame& keyframe, const feature::Frame& frame,
                               const geometry::SE3& T_cam_world, const optim::CameraModel& camera,
                               float radius, int max_distance,
                               std::vector<std::shared_ptr<map::MapPoint>>* points);

}  // namespace moslam::slam
