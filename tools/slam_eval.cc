// Runs slam::System over a data set a few times and prints, per run, the ATE RMSE of the camera
// and keyframe trajectories (TUM convention; SE(3) alignment, Sim(3) for a monocular data set such
// as a KITTI folder without image_1), the median tracking time per frame and local mapping time
// per keyframe, and for monocular runs the frame that initialized the map and the resets; then
// the medians over the runs. Developer measurement (compare with ORB-SLAM2's numbers).
//
//   slam_eval --data ../shared/data/kitti/06_000000-000050
//             --settings configs/KITTI04-12.yaml --runs 3 [--deterministic] [--frames N]
//             [--verbose] [--no-local-ba] [--ba-far-monocular] [--realtime]
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "moslam/eval/statistics.h"
#include "moslam/slam/run_dataset.h"
#include "moslam/util/log.h"

int main(int argc, char** argv) {
  CLI::App app("slam_eval: ATE and timing of moslam's SLAM over repeated runs");
  std::string data, settings, log_level = "warn";
  int runs = 3, frames = 0;
  bool deterministic = false, verbose = false, no_local_ba = false, ba_far_mono = false;
  bool realtime = false;
  app.add_option("--data", data, "data-set folder")->required();
  app.add_option("--settings", settings, "ORB-SLAM2 settings file")->required();
  app.add_option("--runs", runs, "number of runs");
  app.add_option("--frames", frames, "first N frames only (0: all)");
  app.add_flag("--deterministic", deterministic, "mapping synchronously, fixed seeds");
  app.add_flag("--verbose", verbose, "per-frame stage times");
  app.add_flag("--realtime", realtime,
               "frames no faster than their timestamps (threaded mapping gets a live run's time)");
  app.add_flag("--no-local-ba", no_local_ba,
               "local bundle adjustment off (to measure what it contributes)");
  app.add_flag("--ba-far-monocular", ba_far_mono,
               "tracking and BA drop the u_right row of observations beyond ThDepth "
               "(moslam run --far-stereo monocular)");
  app.add_option("--log", log_level, "log level");
  CLI11_PARSE(app, argc, argv);
  moslam::SetupLogging(log_level);
  std::vector<double> ate, kf_ate, track_ms, cpu_ms, map_ms;
  for (int r = 0; r < runs; ++r) {
    const moslam::slam::DatasetRun run = moslam::slam::RunDataset(
        data, settings, deterministic, frames, "",
        [&](moslam::slam::SystemOptions* o) {
          o->local_bundle_adjustment = !no_local_ba;
          if (ba_far_mono) o->far_stereo = moslam::optim::FarStereo::kMonocular;
        },
        realtime);
    if (verbose) {
      for (size_t i = 0; i < run.reports.size(); ++i) {
        const auto& rep = run.reports[i];
        std::printf(
            "frame %3zu %-15s kf=%d matches=%4d inliers=%4d extract=%6.1f track=%6.1f "
            "local=%6.1f kf=%6.1f total=%6.1f %s\n",
            i, moslam::slam::ToString(rep.state), rep.new_keyframe ? 1 : 0, rep.num_matches,
            rep.num_inliers, rep.times.extract_ms, rep.times.track_ms, rep.times.local_map_ms,
            rep.times.keyframe_ms, rep.times.total_ms, rep.reason.c_str());
      }
    }
    std::printf(
        "run %d: frames ok %d/%zu (initialized at frame %d, %d resets, %d lost), ATE RMSE %.4f m "
        "(keyframes %.4f m), median track %.1f ms/frame (CPU %.1f ms), keyframes %d, points %d, "
        "mapping %d steps median %.1f ms\n",
        r + 1, run.frames_ok, run.reports.size(), run.summary.initialized_frame, run.summary.resets,
        run.summary.lost_frames, run.ate_rmse, run.keyframe_ate_rmse, run.track_ms_median,
        run.track_cpu_ms_median, run.summary.keyframes, run.summary.map_points,
        run.summary.mapping_steps, run.summary.mapping_ms_median);
    ate.push_back(run.ate_rmse);
    kf_ate.push_back(run.keyframe_ate_rmse);
    track_ms.push_back(run.track_ms_median);
    cpu_ms.push_back(run.track_cpu_ms_median);
    map_ms.push_back(run.summary.mapping_ms_median);
  }
  std::printf(
      "median over %d runs: ATE RMSE %.4f m (keyframes %.4f m), track %.1f ms/frame (CPU %.1f "
      "ms), mapping %.1f ms/KF\n",
      runs, moslam::eval::Median(ate), moslam::eval::Median(kf_ate), moslam::eval::Median(track_ms),
      moslam::eval::Median(cpu_ms), moslam::eval::Median(map_ms));
  return 0;
}
