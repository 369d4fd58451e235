// One entry point for all data-set readers, for tools that take "a data set folder": the format
// is given or detected from the folder's contents, and the result is the common Sequence.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "moslam/io/euroc.h"
#include "moslam/io/image_folder.h"
#include "moslam/io/kitti.h"
#include "moslam/io/sequence.h"
#include "moslam/io/tum_rgbd.h"

namespace moslam::io {

enum class DatasetFormat { kAuto, kTumRgbd, kKitti, kEuroc, kImageFolder };

// "auto", "tum", "kitti", "euroc", "folder".
const char* ToString(DatasetFormat format);
// The names above, case-insensitive; also "tum-rgbd" and "images".
std::optional<DatasetFormat> ParseDatasetFormat(std::string_view name);

// What a folder looks like, checked in this order: rgb.txt and depth.txt -> TUM RGB-D;
// times.txt and image_0/ or image_2/ -> KITTI; mav0/ (or cam0/data.csv) -> EuRoC; any image
// file -> image folder. nullopt when nothing matches or the folder does not exist.
std::optional<DatasetFormat> DetectDatasetFormat(const std::string& folder);

struct DatasetOptions {
  DatasetFormat format = DatasetFormat::kAuto;  // kAuto: DetectDatasetFormat
  TumRgbdOptions tum;
  KittiOptions kitti;
  EurocOptions euroc;
  double image_folder_rate_hz = 0.0;  // frames per second of an image folder; required there
  bool monocular = false;  // drop right and depth images whatever the data set has (ToMonocular)
};

// Reads `folder` with the reader of its format. Throws InputError when the format cannot be
// detected, and whatever the reader throws.
Sequence ReadDataset(const std::string& folder, const DatasetOptions& options = {});

}  // namespace moslam::io
