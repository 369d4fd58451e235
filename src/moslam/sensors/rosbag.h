// ROS 1 bags (`moslam run --dataset rosbag FILE --topics A,B`), the form in which TUM RGB-D and
// several dynamic-scene data sets are distributed: sensor_msgs/Image topics read with Debian's
// librosbag (rosbag_storage). One topic is a monocular sequence; two are colour and depth
// (RGB-D) when the second one's encoding is a depth encoding (16UC1 in millimetres, 32FC1 in
// metres, as REP 118 defines them), left and right (stereo) otherwise. Colour may be rgb8, bgr8,
// rgba8, bgra8 or mono8. Frames are stamped with the first topic's header stamps; the second
// topic's message of each frame is the one nearest in header stamp, within max_difference_s
// (TUM's associate.py), each used once. The bag is read once for its index of stamps, then each
// frame's messages are read when tracking asks for them (RosbagReader::Read, in the loader
// thread): a bag is never unpacked to disk.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "moslam/io/image.h"
#include "moslam/io/sequence.h"

namespace moslam::sensors {

struct RosbagOptions {
  std::vector<std::string> topics;  // one or two sensor_msgs/Image topics
  double max_difference_s = 0.02;   // the most two messages of one frame may differ (seconds)
  void Check() const;               // InputError naming the option
};

// Whether this moslam was built with librosbag (scripts/setup.sh installs it).
bool RosbagSupported();

class RosbagReader {
 public:
  // Reads the bag's index. InputError naming the bag when it is missing, not a bag, has no
  // such topic (the topics it has are listed), a topic that is not sensor_msgs/Image, an
  // encoding moslam does not read, or no frame whose messages associate.
  RosbagReader(const std::string& path, const RosbagOptions& options);
  ~RosbagReader();
  RosbagReader(const RosbagReader&) = delete;
  RosbagReader& operator=(const RosbagReader&) = delete;

  // Every FrameEntry's image_left is the bag (and image_right / depth the bag for the second
  // topic); the frame is its index. ground_truth_path is unset.
  const io::Sequence& sequence() const;
  // The images of frame `index`: left as `mode` says, right likewise, depth as CV_32FC1 metres
  // (0 where the message has no measurement: 0 or NaN). InputError naming the bag, topic and
  // stamp when a message cannot be read. One thread at a time.
  io::FrameImages Read(int index, io::ColourMode mode);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace moslam::sensors
