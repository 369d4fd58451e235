#include "moslam/io/sequence.h"

#include "moslam/util/strings.h"

namespace moslam::io {

const char* ToString(SensorType sensor) {
  switch (sensor) {
    case SensorType::kMonocular:
      return "monocular";
    case SensorType::kStereo:
      return "stereo";
    case SensorType::kRgbD:
      return "rgbd";
  }
  return "unknown";
}

std::optional<SensorType> ParseSensorType(std::string_view name) {
  const std::string lower = ToLower(Trim(name));
  if (lower == "monocular" || lower == "mono") return SensorType::kMonocular;
  if (lower == "stereo") return SensorType::kStereo;
  if (lower == "rgbd" || lower == "rgb-d") return SensorType::kRgbD;
  return std::nullopt;
}

Sequence ToMonocular(Sequence sequence) {
  sequence.sensor = SensorType::kMonocular;
  for (FrameEntry& frame : sequence.frames) {
    frame.image_right.clear();
    frame.depth.clear();
  }
  if (sequence.calibration) sequence.calibration->bf = 0.0;
  return sequence;
}

}  // namespace moslam::io
