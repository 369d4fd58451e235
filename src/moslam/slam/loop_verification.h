// Checks a loop that place recognition and the Sim(3) estimate have accepted against what the map
// already knows, before it is allowed to move the map. ORB-SLAM2's tests (consistent candidate
// groups over 3 keyframes, >= 20 Sim(3) inliers, >= 40 matches after projection) only ask
// whether two views look alike and fit one similarity; a street of repeated facades or a
// corridor of identical doors passes all of them, because the alias *is* a rigid motion of the
// scene (docs/EVALUATION.md, "False loops"). A false loop corrupts the whole map at once, so each
// rule below is cheap and errs on the side of refusing:
//
//  1. drift bound (and 1b, a return, not a keyframe further along the same way): the correction the
//  loop asks of the current keyframe's pose cannot exceed what
//     odometry could have drifted on the way from the loop keyframe (a floor plus a fraction of
//     the distance travelled, and likewise for the rotation); stereo and RGB-D maps are metric,
//     so a 100 m jump after 300 m of driving is impossible. Pairwise consistency maximization
//     (Mangelson et al. 2018, used by Kimera-RPGO) tests loops against odometry in the same
//     spirit; this is its simplest form, with a distance-travelled bound instead of covariances.
//  2. depth consistency: the loop-side points matched to current keypoints must land at the
//     depths the current keyframe measures there (stereo/RGB-D only);
//  3. neighbours: the loop-side points must also be found from the current keyframe's
//     covisible neighbours, each posed by the loop's correction and its own odometry (ORB-SLAM3's
//     check of a candidate with several covisible keyframes);
//  4. spatial spread: the matches must cover several cells of the image, not one patch.
//
// Pure functions on the map's keyframes; the caller (LoopCloser) holds Map::mutex().
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/geometry/sim3.h"
#include "moslam/map/map.h"
#include "moslam/slam/loop_correction.h"

namespace moslam::slam {

struct LoopVerificationOptions {
  // 1. Drift bound. The corrected camera centre of the current keyframe may lie at most
  // max_drift_floor_m + max_drift_ratio x (path length from the loop keyframe to the current one,
  // in map units) from where odometry put it; its orientation may turn by at most
  // max_rotation_floor_deg + max_rotation_ratio x (rotation accumulated on that path). The ratios
  // are generous: stereo and RGB-D odometry drift about 1 % of the distance (KITTI), so 10 %
  // only refuses what no drift explains. Monocular maps drift in scale too (System sets 0.5).
  bool check_drift = true;
  double max_drift_ratio = 0.1;          // of the path length (1)
  double max_drift_floor_m = 0.3;        // metres (map units)
  double max_rotation_ratio = 0.1;       // of the accumulated rotation (1)
  double max_rotation_floor_deg = 10.0;  // degrees
  // Monocular (Sim(3)) loops: |log scale| of the correction at most this (0: no bound).
  double max_log_scale = 0.7;  // a factor of 2
  // 1b. A loop is a return: the path travelled since the loop keyframe must be at least
  // min_revisit_ratio x the straight distance between the two keyframes (odometry). Driving
  // straight on (KITTI 06), a keyframe that sees what one 15 m back saw but shares too few points
  // with it for the covisibility graph passes every other test, and its "loop" only pulls the
  // map out of shape. 0: no check.
  bool check_revisit = true;
  double min_revisit_ratio = 1.5;
  // 2. Depth consistency (matches whose current keypoint has a depth): the loop-side point's
  // depth in the corrected current camera must agree with the measured depth within
  // depth_tolerance_ratio x depth + 3 x the stereo depth sigma at the keypoint's octave; at
  // least min_depth_consistent of them must agree. Skipped with fewer than min_depth_samples.
  bool check_depth = true;
  double depth_tolerance_ratio = 0.1;
  double min_depth_consistent = 0.6;  // fraction (0-1)
  int min_depth_samples = 10;
  // 3. Neighbours: up to `neighbours` of the current keyframe's best covisible keyframes (not in
  // the loop's group) must each find at least min_neighbour_matches loop-side points by
  // projection; at least min_neighbours_passing of them (or all, when fewer exist; with fewer than
  // two the rule does not apply: loop_room's true loop came with one neighbour that saw little).
  bool check_neighbours = true;
  int neighbours = 3;
  int min_neighbour_matches = 20;
  int min_neighbours_passing = 2;
  // 4. Spatial spread: the matched keypoints of the current keyframe must fall into at least
  // min_spread_cells cells (each holding >= 2 matches) of a spread_cols x spread_rows grid.
  bool check_spread = true;
  int spread_cols = 4;
  int spread_rows = 4;
  int min_spread_cells = 4;
  void Check() const;  // InputError naming the field
};

// What each rule measured, for the log and the tests.
struct LoopVerification {
  bool accepted = false;
  std::string rejected_by;        // "drift", "rotation", "scale", "revisit", "depth", "neighbours",
                                  // "spread"; empty
                                  // when accepted
  double correction_m = 0.0;      // camera-centre correction (map units)
  double correction_deg = 0.0;    // rotation correction
  double path_m = 0.0;            // distance travelled from the loop keyframe (map units)
  double path_deg = 0.0;          // rotation accumulated on the way
  double displacement_m = 0.0;    // odometry distance between the two keyframes
  double log_scale = 0.0;         // of the correction (0 for SE(3) loops)
  int depth_samples = 0;          // matches with a measured depth
  double depth_consistent = 1.0;  // fraction of them that agree
  int neighbours_tried = 0;
  int neighbours_passing = 0;
  int spread_cells = 0;
};

// Distance and rotation travelled from keyframe `from_id` to `to_id` (either order): the sum over
// consecutive keyframes of the map (by id, bad ones skipped) of camera-centre distances and
// relative rotation angles (degrees). Erased keyframes make it a lower bound of the true path.
void PathLength(const map::Map& map, uint64_t from_id, uint64_t to_id, double* metres,
                double* degrees);

// Applies the rules in order and stops at the first that refuses. `bf`: the stereo baseline
// times fx (0 for monocular: the depth rule is skipped).
LoopVerification VerifyLoop(const map::Map& map, const DetectedLoop& loop,
                            const camera::PinholeCamera& camera, double bf,
                            const LoopVerificationOptions& options);

}  // namespace moslam::slam
