#include "moslam/runner/outputs.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "moslam/eval/evaluate.h"
#include "moslam/eval/plot.h"
#include "moslam/eval/report.h"
#include "moslam/eval/statistics.h"
#include "moslam/net/blas_core.h"
#include "moslam/util/atomic_file.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::runner {
namespace fs = std::filesystem;
namespace {

// A CSV field, quoted when it holds a separator or a quote (RFC 4180).
std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

// The per-frame value of one stage over all frames.
template <typename Get>
std::vector<double> Column(const RunResult& result, Get get) {
  std::vector<double> values;
  values.reserve(result.frames.size());
  for (const FrameRecord& f : result.frames) values.push_back(get(f));
  return values;
}

// The same over the frames the mask source ran on (RunOptions::segment_every): the others took no
// segmentation time, and their zeros would hide what one costs.
template <typename Get>
std::vector<double> SegmentedColumn(const RunResult& result, Get get) {
  std::vector<double> values;
  for (const FrameRecord& f : result.frames) {
    if (f.segmented) values.push_back(get(f));
  }
  return values;
}

struct StageColumn {
  const char* name;
  std::vector<double> values;
};

std::vector<StageColumn> StageColumns(const RunResult& r) {
  return {
      {"extract_ms", Column(r, [](const FrameRecord& f) { return f.report.times.extract_ms; })},
      {"track_ms", Column(r, [](const FrameRecord& f) { return f.report.times.track_ms; })},
      {"local_map_ms", Column(r, [](const FrameRecord& f) { return f.report.times.local_map_ms; })},
      {"keyframe_ms", Column(r, [](const FrameRecord& f) { return f.report.times.keyframe_ms; })},
      {"total_ms", Column(r, [](const FrameRecord& f) { return f.report.times.total_ms; })},
      {"mask_ms", Column(r, [](const FrameRecord& f) { return f.mask_ms; })},
      {"seg_ms", Column(r, [](const FrameRecord& f) { return f.network_ms; })},
      {"crf_ms", Column(r, [](const FrameRecord& f) { return f.crf_ms; })}};
}

double Median(std::vector<double> values) { return Percentile(std::move(values), 50.0); }

// Closed loops as [{"time": t, "loop_time": t0}, ...]: the current keyframe's timestamp and the
// one it was closed with.
nlohmann::json LoopsJson(const slam::MapSummary& map) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& [time, loop_time] : map.loop_times) {
    out.push_back({{"time", time}, {"loop_time", loop_time}});
  }
  return out;
}

// Median milliseconds per frame of each part of the pipeline. Segmentation (with its CRF) runs in
// its own thread, concurrently with tracking, so the sustained rate is bounded by the slower of
// `segmentation_total` and `tracking_total`, not by their sum. Local mapping runs in its own
// thread too; its cost per frame is its total over the frames.
nlohmann::json Breakdown(const RunResult& r) {
  const double frames = std::max<double>(1.0, static_cast<double>(r.frames.size()));
  return {{"segmentation",
           Median(SegmentedColumn(r, [](const FrameRecord& f) { return f.network_ms; }))},
          {"crf", Median(SegmentedColumn(r, [](const FrameRecord& f) { return f.crf_ms; }))},
          {"segmentation_total",
           Median(SegmentedColumn(r, [](const FrameRecord& f) { return f.mask_ms; }))},
          {"extraction",
           Median(Column(r, [](const FrameRecord& f) { return f.report.times.extract_ms; }))},
          {"tracking", Median(Column(r,
                                     [](const FrameRecord& f) {
                                       const slam::StageTimes& t = f.report.times;
                                       return t.track_ms + t.local_map_ms + t.keyframe_ms;
                                     }))},
          {"tracking_total",
           Median(Column(r, [](const FrameRecord& f) { return f.report.times.total_ms; }))},
          {"mapping_per_frame", r.map.mapping_ms_total / frames},
          {"mapping_per_keyframe", r.map.mapping_ms_median}};
}

struct StateCounts {
  int ok = 0, lost = 0, not_initialized = 0, keyframes = 0, relocalized = 0, recovered = 0;
  int segmented = 0;  // frames the mask source ran on
};

StateCounts CountStates(const RunResult& result) {
  StateCounts counts;
  for (const FrameRecord& f : result.frames) {
    if (f.report.state == slam::TrackingState::kOk) ++counts.ok;
    if (f.report.state == slam::TrackingState::kLost) ++counts.lost;
    if (f.report.state == slam::TrackingState::kNotInitialized) ++counts.not_initialized;
    if (f.report.new_keyframe) ++counts.keyframes;
    if (f.report.relocalized) ++counts.relocalized;
    if (f.report.recovered) ++counts.recovered;
    if (f.segmented) ++counts.segmented;
  }
  return counts;
}

double Fps(const RunResult& result) {
  return result.wall_s > 0 ? static_cast<double>(result.frames.size()) / result.wall_s : 0.0;
}

nlohmann::json SettingsJson(const RunDescription& d) {
  const io::OrbSlamSettings& s = d.settings;
  return {{"path", d.settings_path},
          {"fx", s.camera.fx},
          {"fy", s.camera.fy},
          {"cx", s.camera.cx},
          {"cy", s.camera.cy},
          {"bf", s.bf},
          {"fps", s.fps},
          {"th_depth", s.th_depth},
          {"depth_map_factor", s.depth_map_factor},
          {"orb_features", s.orb.num_features},
          {"orb_scale_factor", s.orb.scale_factor},
          {"orb_levels", s.orb.num_levels},
          {"orb_ini_th_fast", s.orb.ini_th_fast},
          {"orb_min_th_fast", s.orb.min_th_fast}};
}

}  // namespace

double Percentile(std::vector<double> values, double percent) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double rank = percent / 100.0 * static_cast<double>(values.size() - 1);
  const size_t below = static_cast<size_t>(std::floor(rank));
  const size_t above = std::min(below + 1, values.size() - 1);
  return values[below] + (rank - static_cast<double>(below)) * (values[above] - values[below]);
}

void WriteOrbSlamTum(const eval::Trajectory& trajectory, int pose_decimals,
                     const std::string& path) {
  if (trajectory.size() != trajectory.timestamps.size()) {
    ThrowInFile(path, "a TUM trajectory needs one timestamp per pose");
  }
  std::string out;
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const Eigen::Vector3d& t = trajectory.poses[i].translation();
    const Eigen::Quaterniond& q = trajectory.poses[i].rotation();
    const int p = pose_decimals;
    out += fmt::format("{:.6f} {:.{}f} {:.{}f} {:.{}f} {:.{}f} {:.{}f} {:.{}f} {:.{}f}\n",
                       trajectory.timestamps[i], t.x(), p, t.y(), p, t.z(), p, q.x(), p, q.y(), p,
                       q.z(), p, q.w(), p);
  }
  WriteFileAtomically(path, out, "trajectory");
}

void WriteOrbSlamKitti(const eval::Trajectory& trajectory, const std::string& path) {
  std::string out;
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const geometry::Matrix3x4d m = trajectory.poses[i].Matrix3x4();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c)
        out += fmt::format("{:.9f}{}", m(r, c), r == 2 && c == 3 ? '\n' : ' ');
    }
  }
  WriteFileAtomically(path, out, "trajectory");
}

void WriteFramesCsv(const RunResult& result, const std::string& path) {
  std::string out = std::string(kFramesCsvHeader) + "\n";
  for (const FrameRecord& f : result.frames) {
    const slam::FrameReport& r = f.report;
    out += fmt::format(
        "{},{:.6f},{},{},{},{},{},{},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.4f},{:.3f},{:.3f}"
        ",{},{},{},{:.3f},{},{:.4f},{},{},{:.1f}\n",
        f.index, f.timestamp, StateName(r.state), CsvField(r.reason), r.num_features, r.num_matches,
        r.num_inliers, r.new_keyframe ? 1 : 0, r.times.extract_ms, r.times.track_ms,
        r.times.local_map_ms, r.times.keyframe_ms, r.times.total_ms, f.mask_ms, f.mask_fraction,
        f.network_ms, f.crf_ms, r.relocalized ? 1 : 0, r.recovered ? 1 : 0, f.segmented ? 1 : 0,
        r.times.mask_ms, r.movable_points_erased, r.moving_region_fraction, r.map_keyframes,
        r.map_points, f.rss_mb);
  }
  WriteFileAtomically(path, out, "per-frame log");
}

eval::Trajectory ReadGroundTruth(const io::Sequence& sequence) {
  if (!sequence.ground_truth_path) return {};
  eval::Trajectory gt = eval::ReadTrajectory(*sequence.ground_truth_path);
  const std::string times = (fs::path(sequence.root) / "times.txt").string();
  std::error_code ec;
  if (!gt.has_timestamps() && fs::exists(times, ec)) eval::AttachTimes(times, &gt);
  return gt;
}

void CheckGroundTruth(const io::Sequence& sequence) {
  if (!sequence.ground_truth_path) return;
  const eval::Trajectory gt = ReadGroundTruth(sequence);
  if (gt.empty()) {
    ThrowInFile(*sequence.ground_truth_path, "the data set's ground truth holds no valid pose");
  }
}

std::optional<RunAte> EvaluateRun(const io::Sequence& sequence, const std::string& camera_path,
                                  const std::string& plot_path) {
  if (!sequence.ground_truth_path) return std::nullopt;
  try {
    eval::TrajectoryInputs inputs;
    inputs.gt_path = *sequence.ground_truth_path;
    inputs.est_path = camera_path;
    inputs.est_format = eval::TrajectoryFormat::kTum;
    eval::TrajectoryPair pair = eval::LoadTrajectories(inputs);
    const std::string times = (fs::path(sequence.root) / "times.txt").string();
    std::error_code ec;
    if (!pair.gt.has_timestamps() && fs::exists(times, ec)) eval::AttachTimes(times, &pair.gt);
    eval::EvalRequest request;  // `moslam eval ate`'s defaults: tum convention, se3 alignment
    // Monocular scale is arbitrary: align with a similarity (evo -as).
    if (sequence.sensor == io::SensorType::kMonocular) request.alignment = "sim3";
    const eval::AteOptions options = eval::MakeAteOptions(request, pair);
    RunAte ate{eval::ComputeAte(pair.gt, pair.est, options), {}, {}};
    ate.json = eval::AteToJson(ate.result, pair.gt, pair.est);
    ate.text = eval::FormatAteReport(ate.result, pair.gt, pair.est, /*rotation=*/false);
    if (!plot_path.empty()) {
      eval::WriteTrajectoryPlot(eval::MakeAtePlotData(ate.result, pair.est, false), plot_path);
    }
    return ate;
  } catch (const InputError& e) {
    // A run that tracked too little to align is a result, not a failure of the command.
    spdlog::warn("ATE not computed: {}", e.what());
    return std::nullopt;
  }
}

nlohmann::json SummaryJson(const RunResult& result, const RunDescription& d,
                           const std::optional<RunAte>& ate) {
  const StateCounts counts = CountStates(result);
  nlohmann::json times = nlohmann::json::object();
  for (const StageColumn& column : StageColumns(result)) {
    const eval::ErrorStatistics stats = eval::ComputeStatistics(column.values);
    times[column.name] = {{"median", stats.median},
                          {"mean", stats.mean},
                          {"p90", Percentile(column.values, 90.0)},
                          {"max", stats.max}};
  }
  nlohmann::json json = {{"frames", result.frames.size()},
                         {"frame_range", {result.first, result.last}},
                         {"tracked", counts.ok},
                         {"lost", counts.lost},
                         {"not_initialized", counts.not_initialized},
                         {"relocalized", counts.relocalized},
                         {"recovered", counts.recovered},
                         {"movable_points_erased", result.map.movable_points_erased},
                         {"skipped", result.skipped},
                         {"new_keyframe_frames", counts.keyframes},
                         {"segmented_frames", counts.segmented},
                         {"keyframes", result.map.keyframes},
                         {"map_points", result.map.map_points},
                         {"camera_poses", result.camera.size()},
                         {"mapping",
                          {{"steps", result.map.mapping_steps},
                           {"local_bundle_adjustments", result.map.local_bundle_adjustments},
                           {"median_ms", result.map.mapping_ms_median},
                           {"total_ms", result.map.mapping_ms_total}}},
                         {"loops_closed", result.map.loops_closed},
                         {"loops_rejected", result.map.loops_rejected},
                         {"global_ba_merged", result.map.global_ba_merged},
                         {"loops", LoopsJson(result.map)},
                         {"times_ms", times},
                         {"breakdown_median_ms", Breakdown(result)},
                         {"wall_s", result.wall_s},
                         {"fps", Fps(result)},
                         {"settings", SettingsJson(d)},
                         {"dataset",
                          {{"path", d.dataset_path},
                           {"format", io::ToString(d.format)},
                           {"sensor", io::ToString(d.sensor)}}},
                         {"mask_source", d.mask_source},
                         {"blas_core", net::DescribeOpenBlasCore()},
                         {"segment_every", d.segment_every},
                         {"deterministic", d.deterministic},
                         {"realtime", d.realtime}};
  if (d.deterministic) {
    json["deterministic_mapping"] = {{"frames", d.deterministic_mapping_frames},
                                     {"ms_per_observation", d.deterministic_mapping_ms}};
  }
  if (!d.format_name.empty()) json["dataset"]["format"] = d.format_name;
  // A live source: what it delivered and what tracking had no time for (RunResult::live).
  json["dropped"] = result.live ? result.live->dropped : 0;
  if (result.live) {
    json["live"] = {{"captured", result.live->captured},
                    {"dropped", result.live->dropped},
                    {"max_queued", result.live->max_queued}};
  }
  json["ate"] = ate ? ate->json : nlohmann::json(nullptr);
  // How the run ended: "completed", or "failed" / "interrupted" with why; the counts above are
  // those of the frames tracked until then.
  json["end"] = {{"status", RunEndName(result.end)}, {"message", result.end_message}};
  return json;
}

std::string FormatSummary(const RunResult& result, const RunDescription& d,
                          const std::optional<RunAte>& ate) {
  const StateCounts counts = CountStates(result);
  std::string text;
  text += fmt::format("data set     {} ({}, {})\n", d.dataset_path,
                      d.format_name.empty() ? io::ToString(d.format) : d.format_name.c_str(),
                      io::ToString(d.sensor));
  text += fmt::format(
      "frames       {} ({}:{}): {} tracked, {} lost, {} not initialized{}{}{}\n",
      result.frames.size(), result.first, result.last, counts.ok, counts.lost,
      counts.not_initialized,
      counts.relocalized > 0 ? fmt::format(", {} relocalized", counts.relocalized) : std::string(),
      counts.recovered > 0 ? fmt::format(", {} recovered", counts.recovered) : std::string(),
      result.skipped > 0 ? fmt::format(", {} skipped", result.skipped) : std::string());
  if (result.live) {
    text += fmt::format("live         {} captured, {} dropped while tracking was busy\n",
                        result.live->captured, result.live->dropped);
  }
  text += fmt::format("map          {} keyframes, {} map points\n", result.map.keyframes,
                      result.map.map_points);
  text += fmt::format("masks        {}\n", d.mask_source);
  text += fmt::format("time         {:.2f} s, {:.1f} frames/s{}\n", result.wall_s, Fps(result),
                      d.realtime ? " (real-time pacing)" : "");
  text += "stage ms     median     mean      p90\n";
  for (const StageColumn& column : StageColumns(result)) {
    const eval::ErrorStatistics stats = eval::ComputeStatistics(column.values);
    text += fmt::format("  {:<12} {:8.2f} {:8.2f} {:8.2f}\n", column.name, stats.median, stats.mean,
                        Percentile(column.values, 90.0));
  }
  const nlohmann::json b = Breakdown(result);
  text += fmt::format(
      "per frame    segmentation {:.1f} + CRF {:.1f} ms (own thread) | extraction {:.1f} + "
      "tracking {:.1f} ms | mapping {:.1f} ms (per frame; own thread unless --deterministic)\n",
      b["segmentation"].get<double>(), b["crf"].get<double>(), b["extraction"].get<double>(),
      b["tracking"].get<double>(), b["mapping_per_frame"].get<double>());
  if (result.end != RunEnd::kCompleted) {
    text += fmt::format("ended        {}: {}\n", RunEndName(result.end), result.end_message);
  }
  if (ate) text += "ATE\n" + ate->text;
  return text;
}

void CheckOutputFolder(const std::string& out_dir) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) ThrowInFile(out_dir, "output folder cannot be created: " + ec.message());
  const std::string probe = (fs::path(out_dir) / ".moslam_write_check").string();
  try {
    WriteFileAtomically(probe, "", "write check");
  } catch (const InputError&) {
    ThrowInFile(out_dir, "output folder cannot be written (creating a file there failed)");
  }
  fs::remove(probe, ec);
}

std::string WriteRunOutputs(const io::Sequence& sequence, const RunResult& result,
                            const RunDescription& description, const std::string& out_dir) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) ThrowInFile(out_dir, "output folder cannot be created: " + ec.message());
  const fs::path out(out_dir);
  // Each file is written whole or not at all (util/atomic_file.h); one that fails (a full disk)
  // does not stop the others, summary.json lists it, and the first failure is thrown at the end.
  std::vector<std::string> failures;
  const auto attempt = [&failures](const auto& write) {
    try {
      write();
      return true;
    } catch (const InputError& e) {
      spdlog::error("{}", e.what());
      failures.push_back(e.what());
      return false;
    }
  };
  const std::string camera_path = (out / "CameraTrajectory.txt").string();
  const bool camera = attempt([&] { WriteOrbSlamTum(result.camera, 9, camera_path); });
  if (description.format == io::DatasetFormat::kKitti) {
    attempt(
        [&] { WriteOrbSlamKitti(result.camera, (out / "CameraTrajectory_kitti.txt").string()); });
  }
  attempt([&] { WriteOrbSlamTum(result.keyframes, 7, (out / "KeyFrameTrajectory.txt").string()); });
  if (result.graph) {
    attempt([&] { WriteKeyFrameGraph(*result.graph, (out / "keyframe_graph.json").string()); });
  }
  attempt([&] { WriteFramesCsv(result, (out / "frames.csv").string()); });
  std::optional<RunAte> ate;
  if (camera) {
    attempt([&] { ate = EvaluateRun(sequence, camera_path, (out / "trajectory.png").string()); });
  }
  nlohmann::json summary = SummaryJson(result, description, ate);
  summary["output_errors"] = failures;
  attempt([&] {
    WriteFileAtomically((out / "summary.json").string(), summary.dump(2) + "\n", "run summary");
  });
  if (!failures.empty()) {
    throw InputError(
        fmt::format("{} of the run's outputs in {} could not be written; the first: {}",
                    failures.size(), out_dir, failures.front()));
  }
  spdlog::info("outputs written to {}", out_dir);
  return FormatSummary(result, description, ate);
}

}  // namespace moslam::runner
