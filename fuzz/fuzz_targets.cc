#include "fuzz_targets.h"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>

#include "moslam/eval/trajectory_io.h"
#include "moslam/io/kitti.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/io/tum_rgbd.h"
#include "moslam/map/map.h"
#include "moslam/mapio/map_file.h"
#include "moslam/semantic/model_card.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::fuzz {
namespace fs = std::filesystem;

mapio::MapIdentity FuzzMapIdentity() {
  mapio::MapIdentity id;
  id.sensor = static_cast<int32_t>(io::SensorType::kRgbD);
  id.camera = {525.0, 525.0, 319.5, 239.5, 0.0, 0.0, 0.0, 0.0, 0.0, 40.0};
  id.orb_levels = 8;
  id.orb_scale_factor = 1.2;
  return id;
}

namespace {

// Calls `read` with each of `ways` (every way must run: each reaches other code); throws the
// first InputError when none accepted the file.
template <typename Way, typename Read>
void AcceptedByAny(std::initializer_list<Way> ways, const Read& read) {
  bool accepted = false;
  std::string first_error;
  for (const Way way : ways) {
    try {
      read(way);
      accepted = true;
    } catch (const InputError& e) {
      if (first_error.empty()) first_error = e.what();
    }
  }
  if (!accepted) throw InputError(first_error);
}

// Every sensor: each reads other keys (Camera.bf, DepthMapFactor, ThDepth).
void ParseSettings(const std::string& path, const std::string&) {
  AcceptedByAny({io::SensorType::kMonocular, io::SensorType::kStereo, io::SensorType::kRgbD},
                [&](io::SensorType sensor) { io::LoadOrbSlamSettings(path, sensor); });
}

void ParseTumList(const std::string& path, const std::string&) { io::ReadTumFileList(path); }

// The calibration, then what `moslam run` derives from it.
void ParseKittiCalibration(const std::string& path, const std::string&) {
  const io::KittiCalibration calibration = io::ReadKittiCalibration(path);
  if (calibration.P[0]) io::IntrinsicsFromProjection(*calibration.P[0]);
  if (calibration.P[0] && calibration.P[1]) {
    io::StereoBfFromProjections(*calibration.P[0], *calibration.P[1]);
  }
}

void ParseKittiTimes(const std::string& path, const std::string&) { eval::ReadTimes(path); }

// Detection, then every format explicitly (a file may be read as any of them by `--format`).
void ParseTrajectory(const std::string& path, const std::string&) {
  AcceptedByAny({eval::TrajectoryFormat::kAuto, eval::TrajectoryFormat::kTum,
                 eval::TrajectoryFormat::kKitti, eval::TrajectoryFormat::kEuroc},
                [&](eval::TrajectoryFormat format) { eval::ReadTrajectory(path, format); });
}

// Model files are looked up next to the card, then in `folder` as the shared root: the scratch
// folder holds stand-ins (model.onnx, .mnet, .weights, .cfg), so that cards naming them get past
// the lookup.
void ParseModelCard(const std::string& path, const std::string& folder) {
  semantic::LoadModelCard(path, folder);
}

void ParseVocabulary(const std::string& path, const std::string&) {
  const vocab::Vocabulary vocabulary = vocab::Vocabulary::Load(path);
  if (vocabulary.size() == 0) return;
  const uint8_t descriptor[32] = {};
  vocabulary.Transform(descriptor);  // descends the tree that was loaded
}

// The bytes are a map file's body: the header (magic, version, CRC-32, size) is made here, so
// that mutations reach the records instead of failing the checksum (the header's own checks are
// mapio/map_file's tests).
void ParseMapBody(const std::string& path, const std::string&) {
  std::ifstream file(path, std::ios::binary);
  const std::string body((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  map::Map map;  // owned alone: ParseMap needs no lock
  mapio::ParseMap(mapio::SealMapBody(body), path, FuzzMapIdentity(), &map);
}

// The scratch folder of this process, removed by its destructor at exit (libFuzzer ends with
// exit()). Not an atexit handler: one registered while the static is built runs after the
// static is destroyed (the fuzzers' first finding was that use after free).
class Scratch {
 public:
  Scratch() {
    const char* tmp = std::getenv("TMPDIR");
    const fs::path root = fs::path(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") /
                          ("moslam_fuzz_" + std::to_string(getpid()));
    fs::create_directories(root / "rgb");
    // Files that lists and cards may name: rgb/1.png (a TUM list's image), the model files of
    // the seed cards (fuzz_seeds.cc).
    std::ofstream(root / "rgb" / "1.png") << "x";
    for (const char* model : {"model.onnx", "model.mnet", "model.weights", "model.cfg"}) {
      std::ofstream(root / model) << "x";
    }
    path_ = root.string();
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

const std::string& ScratchFolder() {
  static const Scratch scratch;
  return scratch.path();
}

}  // namespace

const std::vector<FuzzTarget>& Targets() {
  static const std::vector<FuzzTarget> targets = {
      {"settings", "settings.yaml", "io::LoadOrbSlamSettings (ORB-SLAM2 settings YAML)",
       ParseSettings},
      {"tum_list", "rgb.txt", "io::ReadTumFileList (TUM rgb.txt / depth.txt)", ParseTumList},
      {"kitti_calib", "calib.txt", "io::ReadKittiCalibration (KITTI calib.txt)",
       ParseKittiCalibration},
      {"kitti_times", "times.txt", "eval::ReadTimes (KITTI times.txt)", ParseKittiTimes},
      {"trajectory", "trajectory.txt", "eval::ReadTrajectory (TUM, KITTI, EuRoC trajectories)",
       ParseTrajectory},
      {"model_card", "card.yaml", "semantic::LoadModelCard (model cards)", ParseModelCard},
      {"vocabulary", "vocabulary.mvoc", "vocab::Vocabulary::Load (binary and DBoW2 text)",
       ParseVocabulary},
      {"map", "body.map", "mapio::ParseMap (a map file's body)", ParseMapBody},
  };
  return targets;
}

const FuzzTarget& FindTarget(std::string_view name) {
  for (const FuzzTarget& target : Targets()) {
    if (name == target.name) return target;
  }
  MOSLAM_CHECK(false) << "no fuzz target " << name;
  return Targets().front();
}

bool RunOne(const FuzzTarget& target, const std::string& bytes, std::string* error) {
  const std::string folder = ScratchFolder();
  const std::string path = (fs::path(folder) / target.file_name).string();
  {
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    file.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    MOSLAM_CHECK(file.good()) << "cannot write the fuzz input " << path;
  }
  try {
    target.parse(path, folder);
    return true;
  } catch (const InputError& e) {
    if (error != nullptr) *error = e.what();
    return false;
  }
}

bool RunOne(const FuzzTarget& target, const uint8_t* data, size_t size) {
  return RunOne(target, std::string(reinterpret_cast<const char*>(data), size));
}

}  // namespace moslam::fuzz
