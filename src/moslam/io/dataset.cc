#include "moslam/io/dataset.h"

#include <filesystem>

#include <fmt/format.h>

#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam::io {
namespace {

namespace fs = std::filesystem;

bool IsFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

bool IsDir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

bool HasImageFile(const fs::path& folder) {
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code type_ec;
    if (it->is_regular_file(type_ec) && HasImageExtension(it->path().filename().string())) {
      return true;
    }
  }
  return false;
}

}  // namespace

const char* ToString(DatasetFormat format) {
  switch (format) {
    case DatasetFormat::kAuto:
      return "auto";
    case DatasetFormat::kTumRgbd:
      return "tum";
    case DatasetFormat::kKitti:
      return "kitti";
    case DatasetFormat::kEuroc:
      return "euroc";
    case DatasetFormat::kImageFolder:
      return "folder";
  }
  return "unknown";
}

std::optional<DatasetFormat> ParseDatasetFormat(std::string_view name) {
  const std::string lower = ToLower(Trim(name));
  if (lower == "auto") return DatasetFormat::kAuto;
  if (lower == "tum" || lower == "tum-rgbd") return DatasetFormat::kTumRgbd;
  if (lower == "kitti") return DatasetFormat::kKitti;
  if (lower == "euroc") return DatasetFormat::kEuroc;
  if (lower == "folder" || lower == "images") return DatasetFormat::kImageFolder;
  return std::nullopt;
}

std::optional<DatasetFormat> DetectDatasetFormat(const std::string& folder) {
  const fs::path p(folder);
  if (!IsDir(p)) return std::nullopt;
  if (IsFile(p / "rgb.txt") && IsFile(p / "depth.txt")) return DatasetFormat::kTumRgbd;
  if (IsFile(p / "times.txt") && (IsDir(p / "image_0") || IsDir(p / "image_2"))) {
    return DatasetFormat::kKitti;
  }
  if (IsDir(p / "mav0") || IsFile(p / "cam0" / "data.csv")) return DatasetFormat::kEuroc;
  if (HasImageFile(p)) return DatasetFormat::kImageFolder;
  return std::nullopt;
}

Sequence ReadDataset(const std::string& folder, const DatasetOptions& options) {
  DatasetFormat format = options.format;
  if (format == DatasetFormat::kAuto) {
    RequireDirectory(folder, "data set folder");
    const std::optional<DatasetFormat> detected = DetectDatasetFormat(folder);
    if (!detected) {
      ThrowInFile(folder,
                  "unknown data set layout: expected TUM RGB-D (rgb.txt, depth.txt), KITTI "
                  "(times.txt, image_0/), EuRoC (mav0/) or a folder of images");
    }
    format = *detected;
  }
  Sequence sequence;
  switch (format) {
    case DatasetFormat::kTumRgbd:
      sequence = ReadTumRgbd(folder, options.tum);
      break;
    case DatasetFormat::kKitti:
      sequence = ReadKitti(folder, options.kitti);
      break;
    case DatasetFormat::kEuroc:
      sequence = ReadEuroc(folder, options.euroc);
      break;
    case DatasetFormat::kImageFolder:
      sequence = ReadImageFolder(folder, options.image_folder_rate_hz);
      break;
    case DatasetFormat::kAuto:
      break;  // resolved above
  }
  if (options.monocular) return ToMonocular(std::move(sequence));
  return sequence;
}

}  // namespace moslam::io
