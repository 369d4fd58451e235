// A Kinect v1 (Xbox 360) as a live RGB-D source (`moslam run --dataset kinect INDEX`) through
// Debian's libfreenect (libfreenect-dev): 640x480 colour and depth registered to it by the
// device's factory calibration (FREENECT_DEPTH_REGISTERED, millimetres; converted to metres),
// 30 frames per second, stamped with the host's clock (io::LiveClock) when both have arrived.
#pragma once

#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "moslam/io/live_source.h"

namespace moslam::sensors {

// Whether this moslam was built with libfreenect (scripts/setup.sh installs it).
bool KinectSupported();

// "0" -> 0; InputError for anything but a whole number >= 0.
int ParseKinectIndex(const std::string& text);

// Opens Kinect number `index`. `size`: the size the settings' intrinsics are for (0x0: any);
// the Kinect gives 640x480 only. InputError naming "kinect:<index>" when libfreenect cannot
// start (no USB access), finds no such device, the size differs, or this moslam was built
// without libfreenect.
std::unique_ptr<io::LiveSource> OpenKinect(int index, const cv::Size& size);

}  // namespace moslam::sensors
