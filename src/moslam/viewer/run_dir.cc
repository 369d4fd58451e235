#include "moslam/viewer/run_dir.h"

#include <filesystem>
#include <fstream>

#include <spdlog/spdlog.h>

#include "moslam/eval/trajectory_io.h"
#include "moslam/io/dataset.h"
#include "moslam/map/map.h"
#include "moslam/mapio/map_file.h"
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
      for (const auto& [id, keyframe] : map.keyframes())
        v.keyframes.push_back(keyframe->T_world_cam());
      view->snapshot.view = std::move(v);
      view->map_path = path;
      return true;
    } catch (const InputError& e) {
      spdlog::warn("view: {} not drawn: {}", path, e.what());
    }
  }
  return false;
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
  if (!LoadFinalMap(dir, &view)) {
    const fs::path keyframes = dir / "KeyFrameTrajectory.txt";
    slam::SystemView v;
    if (fs::exists(keyframes)) v.keyframes = eval::ReadTrajectory(keyframes.string()).poses;
    view.snapshot.view = std::move(v);
  }
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
