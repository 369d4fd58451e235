// V4L2 cameras through OpenCV's VideoCapture (`moslam run --dataset camera DEVICE`): one device
// for a monocular camera, two for a stereo pair (left, right), or one device whose frames hold
// the left and right images side by side (many USB stereo cameras). Frames are stamped with the
// host's clock when both devices have delivered (LiveClock), as nothing else is shared by two
// cameras.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/io/live_source.h"

namespace moslam::io {

struct CameraOptions {
  // "/dev/videoN" or an index "N" (= /dev/videoN). One: monocular, or stereo with side_by_side;
  // two: stereo, left then right.
  std::vector<std::string> devices;
  bool side_by_side = false;  // one device, left image in the frame's left half
  // The size asked of the device (the settings' Camera.width x Camera.height, the size the
  // intrinsics are for; for side_by_side the size of one half); 0x0: the device's own. A device
  // that delivers another size is an error naming it.
  cv::Size size;
  double fps = 0.0;    // frames per second asked of the device; 0: its own
  void Check() const;  // InputError naming the field
};

// "0" -> "/dev/video0"; anything else unchanged.
std::string CameraDevicePath(const std::string& device);

// Opens the devices. InputError naming the device when it does not exist, is not a character
// device, cannot be opened by OpenCV's V4L2 backend (busy, no permission, not a capture device)
// or delivers another size than asked.
std::unique_ptr<LiveSource> OpenCamera(const CameraOptions& options);

}  // namespace moslam::io
