#include "moslam/io/euroc.h"

#include <filesystem>
#include <unordered_map>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "moslam/io/index_file.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam::io {
namespace {

namespace fs = std::filesystem;

struct CameraEntry {
  long long stamp_ns = 0;
  std::string image;
};

// Nanoseconds -> seconds without going through a double of ~1e18, which would round the stamp to
// ~256 ns before the division.
double NanosecondsToSeconds(long long ns) {
  return static_cast<double>(ns / 1000000000LL) + static_cast<double>(ns % 1000000000LL) * 1e-9;
}

std::vector<CameraEntry> ReadCameraCsv(const std::string& camera_folder) {
  const std::string csv = (fs::path(camera_folder) / "data.csv").string();
  const std::string data = (fs::path(camera_folder) / "data").string();
  std::vector<CameraEntry> entries;
  std::optional<long long> previous;
  for (const TextLine& line : ReadDataLines(csv)) {
    const auto fields = internal::SplitExactly(csv, line, 2, true, "'timestamp [ns],filename'");
    const std::optional<long long> stamp = ParseInt(fields[0]);
    if (!stamp || *stamp < 0) {
      ThrowAtLine(csv, line.number,
                  fmt::format("timestamp '{}' is not a non-negative integer of nanoseconds",
                              Excerpt(fields[0])));
    }
    if (previous && *stamp <= *previous) {
      ThrowAtLine(csv, line.number,
                  fmt::format("timestamp {} ns does not increase (previous entry: {} ns); entries "
                              "must be in strictly increasing time order",
                              *stamp, *previous));
    }
    previous = *stamp;
    CameraEntry entry{*stamp, internal::ResolvePath(data, fields[1])};
    internal::RequireListedFile(csv, line.number, entry.image);
    entries.push_back(std::move(entry));
  }
  if (entries.empty()) ThrowInFile(csv, "lists no images");
  return entries;
}

std::string Mav0Folder(const std::string& folder) {
  RequireDirectory(folder, "EuRoC sequence folder");
  std::error_code ec;
  if (fs::is_directory(fs::path(folder) / "mav0", ec)) return (fs::path(folder) / "mav0").string();
  if (fs::is_directory(fs::path(folder) / "cam0", ec)) return folder;  // given mav0/ itself
  ThrowInFile(folder, "is not a EuRoC sequence folder: it has neither mav0/ nor cam0/");
}

}  // namespace

Sequence ReadEuroc(const std::string& folder, const EurocOptions& options) {
  const std::string mav0 = Mav0Folder(folder);
  const std::vector<CameraEntry> left = ReadCameraCsv((fs::path(mav0) / "cam0").string());
  std::error_code ec;
  const bool stereo = !options.monocular && fs::is_directory(fs::path(mav0) / "cam1", ec);

  Sequence sequence;
  sequence.name = internal::FolderName(mav0 + "/..");  // the folder that holds mav0/
  sequence.root = folder;
  sequence.sensor = stereo ? SensorType::kStereo : SensorType::kMonocular;

  std::unordered_map<long long, const CameraEntry*> right_by_stamp;
  std::vector<CameraEntry> right;
  if (stereo) {
    right = ReadCameraCsv((fs::path(mav0) / "cam1").string());
    for (const CameraEntry& e : right) right_by_stamp[e.stamp_ns] = &e;
  }
  size_t unpaired = 0;
  for (const CameraEntry& l : left) {
    FrameEntry frame;
    frame.timestamp = NanosecondsToSeconds(l.stamp_ns);
    frame.image_left = l.image;
    if (stereo) {
      const auto it = right_by_stamp.find(l.stamp_ns);
      if (it == right_by_stamp.end()) {
        ++unpaired;
        continue;
      }
      frame.image_right = it->second->image;
    }
    frame.index = static_cast<int>(sequence.frames.size());
    sequence.frames.push_back(std::move(frame));
  }
  if (unpaired > 0) {
    spdlog::warn("{}: {} of {} cam0 images have no cam1 image with the same stamp; dropped", mav0,
                 unpaired, left.size());
  }
  if (sequence.frames.empty()) {
    ThrowInFile(mav0, "no cam0 image has a cam1 image with the same stamp: no stereo frames");
  }
  sequence.ground_truth_path = internal::ExistingFile(mav0, "state_groundtruth_estimate0/data.csv");
  return sequence;
}

}  // namespace moslam::io
