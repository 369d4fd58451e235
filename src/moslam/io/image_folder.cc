#include "moslam/io/image_folder.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "moslam/io/index_file.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam::io {

namespace fs = std::filesystem;

bool HasImageExtension(const std::string& filename) {
  const std::string ext = ToLower(fs::path(filename).extension().string());
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".ppm" ||
         ext == ".bmp";
}

Sequence ReadImageFolder(const std::string& folder, double rate_hz) {
  RequireDirectory(folder, "image folder");
  if (!std::isfinite(rate_hz) || !(rate_hz > 0.0)) {
    ThrowInFile(folder, fmt::format("frame rate must be a positive number of Hz, got {}", rate_hz));
  }
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    std::error_code type_ec;
    if (it->is_regular_file(type_ec) && HasImageExtension(name)) names.push_back(name);
  }
  if (ec) ThrowInFile(folder, fmt::format("cannot list the folder: {}", ec.message()));
  if (names.empty()) {
    ThrowInFile(folder, "contains no images (.png, .jpg, .jpeg, .pgm, .ppm or .bmp files)");
  }
  std::sort(names.begin(), names.end());

  Sequence sequence;
  sequence.name = internal::FolderName(folder);
  sequence.root = folder;
  sequence.sensor = SensorType::kMonocular;
  for (size_t i = 0; i < names.size(); ++i) {
    FrameEntry frame;
    frame.index = static_cast<int>(i);
    frame.timestamp = static_cast<double>(i) / rate_hz;
    frame.image_left = (fs::path(folder) / names[i]).string();
    sequence.frames.push_back(std::move(frame));
  }
  return sequence;
}

}  // namespace moslam::io
