// Loop closing (ORB-SLAM2's LoopClosing, Mur-Artal & Tardós 2017, Sec. V; ORB-SLAM, Mur-Artal et
// al. 2015, Sec. VI), one keyframe at a time after local mapping:
//  1. detection: bag-of-words candidates scoring at least the current keyframe's worst covisible
//     neighbour (KeyFrameDatabase::DetectLoopCandidates), scores taken with the words that
//     recently passed places also hold down-weighted (RecentWordWeights: repeated structure),
//     kept only when a candidate's covisibility group was consistent with those of the previous
//     3 keyframes;
//  2. Sim(3) with each candidate: bag-of-words matches of their map points (SearchByBoW), RANSAC
//     (slam/sim3_solver.h), guided matching (SearchBySim3), refinement (optim::OptimizeSim3),
//     accepted with >= 20 inliers, then the points of the candidate's covisible keyframes
//     projected into the current one: >= 40 matches make a loop;
//  2b. verification against the map (slam/loop_verification.h): the correction within the drift
//     odometry allows, a return (not a keyframe further along the way), depths, the current
//     keyframe's neighbours, the matches' spread; a refused
//     loop moves nothing; of the loops that pass, the one with the smallest correction is closed;
//  3. correction (slam/loop_correction.h): Sim(3) propagation, point fusion, essential graph;
//  4. a global bundle adjustment of a copy of the map in a thread of its own, merged when done.
//
// The keyframe database is filled by local mapping (slam/keyframe_database.h), which runs before
// this on every keyframe. ProcessKeyFrame is a synchronous step: System calls it in its
// loop-closing thread, fed by a bounded queue of keyframes that local mapping has processed, or
// directly in deterministic mode (where the global bundle adjustment also runs in the caller's
// thread). Locking: see map/map.h; ProcessKeyFrame holds Map::mutex() for detection, Sim(3)
// estimation and the whole correction. Scratch state (consistent groups, the last loop, earlier
// loop edges) lives here.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <set>
#include <thread>
#include <utility>
#include <vector>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/map/map.h"
#include "moslam/optim/observation.h"
#include "moslam/slam/keyframe_database.h"
#include "moslam/slam/loop_correction.h"
#include "moslam/slam/loop_verification.h"

namespace moslam::slam {

struct LoopCloserOptions {
  bool fix_scale = true;  // stereo/RGB-D: SE(3) loop transforms; false: Sim(3) (monocular)
  int min_keyframes_between_loops = 10;  // ORB-SLAM2: 10
  int consistency = 3;                   // consecutive consistent keyframes (ORB-SLAM2: 3)
  int min_point_matches = 20;            // descriptor matches to try a candidate (ORB-SLAM2: 20)
  int min_sim3_inliers = 20;             // after RANSAC and after refinement (ORB-SLAM2: 20)
  int min_loop_matches = 40;             // after projecting the loop side (ORB-SLAM2: 40)
  // Repeated structure (slam/keyframe_database.h, RecentWordWeights): the BoW scores of the
  // detection down-weight the words held by the last `recent_word_keyframes` keyframes that
  // are out of view of the current one (0: off, ORB-SLAM2's scores), once at least
  // `min_recent_word_keyframes` of them exist.
  int recent_word_keyframes = 20;
  int min_recent_word_keyframes = 5;
  // Checks of a found loop against the map before it is corrected (slam/loop_verification.h);
  // verify = false closes every loop that passed ORB-SLAM2's tests (moslam run
  // --no-loop-verification, for comparisons).
  bool verify = true;
  LoopVerificationOptions verification;
  bool global_bundle_adjustment = true;  // after each closed loop
  // The global BA's weight of far stereo rows (as the local BA's, LocalMapperOptions::far_stereo).
  optim::FarStereoWeighting far_stereo;
  bool synchronous = false;  // global BA in the caller's thread (deterministic mode)
  int num_threads = 1;       // Ceres threads in the global BA
  uint64_t seed = 1;         // RANSAC (mixed with the keyframe id)
  void Check() const;        // InputError naming the field
};

struct LoopCloserStats {
  int keyframes = 0;              // processed
  int candidates_consistent = 0;  // keyframes with a consistent candidate
  int loops_closed = 0;
  int loops_rejected = 0;  // found (ORB-SLAM2's tests passed) but refused by the verification
  int global_ba_merged = 0;
  int global_ba_dropped = 0;                          // stale (another correction meanwhile)
  std::vector<std::pair<uint64_t, uint64_t>> loops;   // (current, loop) keyframe ids
  std::vector<std::pair<double, double>> loop_times;  // their timestamps (s), as `loops`
};

class LoopCloser {
 public:
  LoopCloser(map::Map* map, const camera::PinholeCamera& camera, double bf,
             KeyFrameDatabase* database, const LoopCloserOptions& options);
  ~LoopCloser();  // waits for a running global bundle adjustment

  // Returns true when this keyframe closed a loop.
  bool ProcessKeyFrame(const std::shared_ptr<map::KeyFrame>& keyframe);
  // Waits until a global bundle adjustment in flight has been merged or dropped.
  void WaitForGlobalBundleAdjustment();
  LoopCloserStats Stats() const;

 private:
  bool DetectLoop(const std::shared_ptr<map::KeyFrame>& kf,
                  std::vector<std::shared_ptr<map::KeyFrame>>* consistent);
  bool ComputeSim3(const std::shared_ptr<map::KeyFrame>& kf,
                   const std::vector<std::shared_ptr<map::KeyFrame>>& candidates,
                   DetectedLoop* loop);
  // VerifyLoop with the log line and the stats of a refusal.
  LoopVerification Verify(const DetectedLoop& loop, int inliers, int matches);
  void StartGlobalBundleAdjustment();
  void RunGlobalBundleAdjustment(GlobalBundleJob job);

  map::Map* map_;
  camera::PinholeCamera camera_;
  double bf_ = 0.0;
  optim::CameraModel model_;
  KeyFrameDatabase* database_;
  LoopCloserOptions options_;
  struct ConsistentGroup {
    std::set<uint64_t> keyframes;
    int consistency = 0;
  };
  std::vector<ConsistentGroup> groups_;
  uint64_t last_loop_keyframe_ = 0;
  std::thread gba_thread_;
  mutable std::mutex stats_mutex_;
  LoopCloserStats stats_;
};

}  // namespace moslam::slam
