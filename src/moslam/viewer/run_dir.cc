#include "moslam/viewer/run_dir.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <utility>
#include <vector>

#include <spdlog/spdlog.h>

#include "moslam/eval/trajectory_io.h"
#include "moslam/io/dataset.h"
#include "moslam/map/keyframe_graph.h"
#include "moslam/map/map.h"
#include "moslam/mapio/map_file.h"
#include "moslam/runner/keyframe_graph.h"
#include "moslam/runner/outputs.h"
#include "moslam/util/error.h"

namespace moslam::viewer {
namespace fs = std::filesystem;
namespace {

nlohmann::json ReadSummary(const fs::path& path) {
  std::ifstream in(path);
  if (!in) ThrowInFile(path.string(), "no summary.json: not a folder written by `moslam run`");
  nlohmann::json json = nlohmann::json::parse(in, nullptr, false);
  if (json.is_discarded() || !json.is_object()) ThrowInFile(path.string(), "not a JSON object");
  return json;
}

void AppendPositions(const eval::Trajectory& t, std::vector<float>* out) {
  for (const geometry::SE3& pose : t.poses) {
    const Eigen::Vector3d& p = pose.translation();
    out->insert(out->end(),
                {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
  }
}

// The data set's ground truth, aligned to the run's first pose; empty when the data set is gone.
std::vector<float> GroundTruth(const nlohmann::json& summary, const eval::Trajectory& camera) {
  if (camera.empty() || !summary.contains("dataset")) return {};
  try {
    const nlohmann::json& d = summary["dataset"];
    io::DatasetOptions options;
    const auto format = io::ParseDatasetFormat(d.value("format", "auto"));
    if (format) options.format = *format;
    const io::Sequence sequence = io::ReadDataset(d.value("path", ""), options);
    const eval::Trajectory gt = runner::ReadGroundTruth(sequence);
    return AlignGroundTruth(gt, camera.timestamps.front(), camera.poses.front(),
                            camera.timestamps.back());
  } catch (const std::exception& e) {
    spdlog::warn("view: no ground truth ({})", e.what());
    return {};
  }
}

// The first *.map file of the folder that loads, drawn as the final map.
bool LoadFinalMap(const fs::path& run_dir, RunView* view) {
  for (const auto& entry : fs::directory_iterator(run_dir)) {
    if (entry.path().extension() != ".map") continue;
    const std::string path = entry.path().string();
    try {
      map::Map map;
      mapio::LoadMap(path, mapio::ReadMapIdentity(path), &map);
      slam::SystemView v;
      for (const auto& [id, point] : map.points()) {
        const Eigen::Vector3f p = point->position.cast<float>();
        v.points.insert(v.points.end(), {p.x(), p.y(), p.z()});
        v.point_states.push_back(static_cast<uint8_t>(slam::ViewPointState::kMap));
      }
      // The keyframes and their whole graph, as the live page's final picture has them.
      map::IndexedKeyFrameGraph graph =
          map::IndexKeyFrameGraph(map, /*with_graph=*/true, slam::kViewCovisibilityMinWeight);
      v.keyframes = std::move(graph.poses);
      v.loops = std::move(graph.loops);
      v.covisibility = std::move(graph.covisibility);
      v.spanning_tree = std::move(graph.spanning_tree);
      v.has_graph = true;
      view->snapshot.view = std::move(v);
      view->map_path = path;
      view->graph_from = path;
      return true;
    } catch (const InputError& e) {
      spdlog::warn("view: {} not drawn: {}", path, e.what());
    }
  }
  return false;
}

// Whether the keyframes of a graph file are those of KeyFrameTrajectory.txt (6 decimals there).
bool SameKeyFrames(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (size_t k = 0; k < a.size(); ++k) {
    if (std::abs(a[k] - b[k]) > 2e-6) return false;
  }
  return true;
}

// The closed loops of summary.json (the timestamps of each loop's two keyframes) by index into
// `timestamps`, for a folder written before keyframe_graph.json was; a loop whose keyframe is not
// found is left out.
std::vector<uint32_t> LoopsFromSummary(const nlohmann::json& summary,
                                       const std::vector<double>& timestamps) {
  const auto find = [&timestamps](double t) -> std::optional<uint32_t> {
    for (size_t k = 0; k < timestamps.size(); ++k) {
      if (std::abs(timestamps[k] - t) <= 2e-6) return static_cast<uint32_t>(k);
    }
    return std::nullopt;
  };
  std::vector<std::pair<uint32_t, uint32_t>> loops;  // (current, loop), as the view orders them
  const nlohmann::json none = nlohmann::json::array();
  const nlohmann::json& list = summary.contains("loops") ? summary["loops"] : none;
  for (const nlohmann::json& loop : list) {
    if (!loop.is_object()) continue;
    const auto current = find(loop.value("time", -1.0));
    const auto other = find(loop.value("loop_time", -1.0));
    if (current && other) loops.emplace_back(*current, *other);
  }
  std::sort(loops.begin(), loops.end());
  std::vector<uint32_t> out;
  for (const auto& [current, other] : loops) out.insert(out.end(), {other, current});
  return out;
}

// Without a map file: the keyframes of KeyFrameTrajectory.txt and their graph from
// keyframe_graph.json (`moslam run` writes it), or only the loops of summary.json for an older
// folder. A graph whose keyframes are not those is left out (a warning).
void LoadKeyFrames(const fs::path& dir, const nlohmann::json& summary, RunView* view) {
  slam::SystemView v;
  eval::Trajectory keyframes;
  if (fs::exists(dir / "KeyFrameTrajectory.txt")) {
    keyframes = eval::ReadTrajectory((dir / "KeyFrameTrajectory.txt").string());
    v.keyframes = keyframes.poses;
  }
  const fs::path graph_path = dir / "keyframe_graph.json";
  if (fs::exists(graph_path)) {
    runner::KeyFrameGraph graph = runner::ReadKeyFrameGraph(graph_path.string());
    if (SameKeyFrames(graph.timestamps, keyframes.timestamps)) {
      v.loops = std::move(graph.loops);
      v.covisibility = std::move(graph.covisibility);
      v.spanning_tree = std::move(graph.spanning_tree);
      v.has_graph = true;
      view->graph_from = graph_path.string();
    } else {
      spdlog::warn("view: {} is not of the keyframes of KeyFrameTrajectory.txt: not drawn",
                   graph_path.string());
    }
  } else {
    v.loops = LoopsFromSummary(summary, keyframes.timestamps);
    if (!v.loops.empty()) view->graph_from = "summary.json (loops only)";
  }
  view->snapshot.view = std::move(v);
}

}  // namespace

RunView LoadRunView(const std::string& run_dir) {
  const fs::path dir(run_dir);
  if (!fs::is_directory(dir)) ThrowInput("view: {} is no folder", run_dir);
  const nlohmann::json summary = ReadSummary(dir / "summary.json");
  const eval::Trajectory camera = eval::ReadTrajectory((dir / "CameraTrajectory.txt").string());
  RunView view;
  AppendPositions(camera, &view.picture.trajectory);
  view.picture.ground_truth = GroundTruth(summary, camera);
  if (!LoadFinalMap(dir, &view)) LoadKeyFrames(dir, summary, &view);
  if (!camera.empty()) view.snapshot.T_world_cam = camera.poses.back();
  view.snapshot.numbers = {
      {"type", "frame"},
      {"finished", true},
      {"replay", true},
      {"run", run_dir},
      {"end", summary.value("end", nlohmann::json::object()).value("status", "")},
      {"frames", summary.value("frames", 0)},
      {"keyframes", summary.value("keyframes", 0)},
      {"map_points", summary.value("map_points", 0)},
      {"fps", summary.value("fps", 0.0)},
      {"state", "finished"}};
  if (!camera.empty()) view.snapshot.numbers["timestamp"] = camera.timestamps.back();
  return view;
}

}  // namespace moslam::viewer
