// The map-changing half of loop closing (ORB-SLAM2's LoopClosing::CorrectLoop,
// Optimizer::OptimizeEssentialGraph and LoopClosing::RunGlobalBundleAdjustment; Mur-Artal &
// Tardós 2017, Sec. V; Strasdat et al. 2010 for the Sim(3) pose graph).
//
// Caller holds Map::mutex() for CorrectLoop and for the Prepare/Merge steps of the global bundle
// adjustment; SolveGlobalBundleAdjustment runs without it on the copy.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <utility>
#include <vector>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/geometry/sim3.h"
#include "moslam/map/map.h"
#include "moslam/optim/bundle_adjuster.h"
#include "moslam/optim/pose_graph.h"
#include "moslam/slam/loop_matching.h"

namespace moslam::slam {

struct DetectedLoop {
  std::shared_ptr<map::KeyFrame> current;
  std::shared_ptr<map::KeyFrame> loop;
  geometry::Sim3 S_cur_world;  // the current keyframe's pose corrected by the loop
  // Per keypoint of `current`: the loop-side map point matched to it (Sim3 inliers, guided and
  // projection matches).
  PointMatches matched;
  // Map points of the loop keyframe and its covisible keyframes (fused into the current side).
  std::vector<std::shared_ptr<map::MapPoint>> loop_points;
};

struct LoopCorrectionStats {
  int corrected_keyframes = 0;  // by the Sim(3) propagation (the current neighbourhood)
  int fused_points = 0;
  int graph_vertices = 0;
  int graph_edges = 0;
  double graph_initial_cost = 0.0;
  double graph_final_cost = 0.0;
};

// Propagates the loop's Sim(3) to the current keyframe's covisible neighbourhood (and to
// keyframes newer than it, tracked meanwhile) and their points, fuses the duplicated points, adds
// the new loop connections, optimizes the essential graph (spanning tree, covisibility >= 100,
// `loop_edges` of earlier loops, the new loop links; the loop keyframe fixed) and moves every
// keyframe and point with the result. `fix_scale`: stereo/RGB-D (6 DoF); false: monocular (7).
LoopCorrectionStats CorrectLoop(map::Map* map, const DetectedLoop& loop,
                                const std::set<std::pair<uint64_t, uint64_t>>& loop_edges,
                                const camera::PinholeCamera& camera, bool fix_scale);

// A copy of the whole map as a bundle-adjustment problem (ORB-SLAM2's GlobalBundleAdjustemnt);
// the oldest keyframe is fixed.
struct GlobalBundleJob {
  optim::BundleProblem problem;
  std::vector<uint64_t> keyframe_ids;  // per pose
  std::vector<uint64_t> point_ids;     // per point
  uint64_t generation = 0;             // Map::generation() when copied
};
// `far`: how far stereo rows are weighed (as in local bundle adjustment).
GlobalBundleJob PrepareGlobalBundleAdjustment(const map::Map& map, const optim::CameraModel& camera,
                                              const optim::FarStereoWeighting& far = {});
// Without the lock.
optim::BundleResult SolveGlobalBundleAdjustment(const GlobalBundleJob& job, int num_threads);
// Writes the result back unless the map's generation changed since the copy (another loop was
// corrected meanwhile: the result is stale and dropped, returns false). Keyframes created after
// the copy follow their spanning-tree parent's correction, points not in the copy their reference
// keyframe's (ORB-SLAM2's RunGlobalBundleAdjustment). Bumps the generation.
bool MergeGlobalBundleAdjustment(map::Map* map, const GlobalBundleJob& job,
                                 const optim::BundleResult& result);

}  // namespace moslam::slam
