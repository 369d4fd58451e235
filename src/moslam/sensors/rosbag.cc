#include "moslam/sensors/rosbag.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <utility>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgproc.hpp>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

#if MOSLAM_HAVE_ROSBAG
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>
#endif

namespace moslam::sensors {

void RosbagOptions::Check() const {
  if (topics.empty() || topics.size() > 2) {
    ThrowInput("--topics: one image topic (monocular) or two (colour,depth or left,right), got {}",
               topics.size());
  }
  if (topics.size() == 2 && topics[0] == topics[1]) {
    ThrowInput("--topics: the same topic twice ({})", topics[0]);
  }
  if (!(max_difference_s > 0.0) || !std::isfinite(max_difference_s)) {
    ThrowInput("rosbag.max_difference_s: must be > 0 seconds, got {}", max_difference_s);
  }
}

#if MOSLAM_HAVE_ROSBAG

namespace {

bool IsDepthEncoding(const std::string& encoding) {
  return encoding == "16UC1" || encoding == "32FC1";
}
bool IsColourEncoding(const std::string& encoding) {
  return encoding == "rgb8" || encoding == "bgr8" || encoding == "rgba8" || encoding == "bgra8" ||
         encoding == "mono8";
}

// One message of a topic, as the index keeps it: enough to find it again and to stamp frames.
struct IndexEntry {
  ros::Time bag_time;  // when it was written into the bag (what a View's time range selects)
  ros::Time stamp;     // its header stamp (what frames are stamped and associated with)
};

struct Topic {
  std::string name;
  std::string encoding;              // of its first message; every message must have it
  std::vector<IndexEntry> messages;  // sorted by header stamp
};

// The message's pixels as a cv::Mat header over its data (not copied), after checking that
// the sizes agree: a broken message is an InputError, not a read past its end.
cv::Mat Wrap(const sensor_msgs::Image& image, const std::string& where) {
  int type = CV_8UC1;
  if (image.encoding == "rgb8" || image.encoding == "bgr8") type = CV_8UC3;
  if (image.encoding == "rgba8" || image.encoding == "bgra8") type = CV_8UC4;
  if (image.encoding == "16UC1") type = CV_16UC1;
  if (image.encoding == "32FC1") type = CV_32FC1;
  if (!IsColourEncoding(image.encoding) && !IsDepthEncoding(image.encoding)) {
    ThrowInput("{}: encoding '{}' is none of rgb8, bgr8, rgba8, bgra8, mono8, 16UC1, 32FC1", where,
               image.encoding);
  }
  const size_t row = static_cast<size_t>(image.width) * CV_ELEM_SIZE(type);
  if (image.width == 0 || image.height == 0 || image.step < row ||
      image.data.size() < static_cast<size_t>(image.step) * image.height) {
    ThrowInput("{}: {}x{} {} image with step {} and {} bytes of data does not hold its pixels",
               where, image.width, image.height, image.encoding, image.step, image.data.size());
  }
  if (image.is_bigendian && CV_ELEM_SIZE1(type) > 1) {
    ThrowInput("{}: big-endian {} data is not read (this host is little-endian)", where,
               image.encoding);
  }
  return cv::Mat(static_cast<int>(image.height), static_cast<int>(image.width), type,
                 const_cast<uint8_t*>(image.data.data()), image.step);
}

cv::Mat ToColourMode(const cv::Mat& pixels, const std::string& encoding, io::ColourMode mode) {
  cv::Mat out;
  const bool grey = mode == io::ColourMode::kGrey;
  if (encoding == "mono8") {
    if (grey) return pixels.clone();
    cv::cvtColor(pixels, out, cv::COLOR_GRAY2BGR);
  } else if (encoding == "bgr8") {
    if (!grey) return pixels.clone();
    cv::cvtColor(pixels, out, cv::COLOR_BGR2GRAY);
  } else if (encoding == "rgb8") {
    cv::cvtColor(pixels, out, grey ? cv::COLOR_RGB2GRAY : cv::COLOR_RGB2BGR);
  } else if (encoding == "bgra8") {
    cv::cvtColor(pixels, out, grey ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGRA2BGR);
  } else {  // rgba8
    cv::cvtColor(pixels, out, grey ? cv::COLOR_RGBA2GRAY : cv::COLOR_RGBA2BGR);
  }
  return out;
}

// Depth in metres, 0 where there is no measurement (0 in 16UC1; 0, NaN or inf in 32FC1).
cv::Mat ToMetres(const cv::Mat& pixels) {
  cv::Mat metres;
  if (pixels.type() == CV_16UC1) {
    pixels.convertTo(metres, CV_32F, 1.0 / 1000.0);  // REP 118: millimetres
    return metres;
  }
  metres = pixels.clone();
  metres.forEach<float>([](float& d, const int*) {
    if (!std::isfinite(d) || d < 0.0f) d = 0.0f;
  });
  return metres;
}

}  // namespace

struct RosbagReader::Impl {
  std::string path;
  rosbag::Bag bag;
  std::vector<Topic> topics;
  io::Sequence sequence;
  // Per frame, the index of its message in each topic.
  std::vector<std::pair<size_t, size_t>> frame_messages;

  std::string Where(const Topic& topic, const ros::Time& stamp) const {
    return fmt::format("{}: topic {}, message stamped {:.6f}", path, topic.name, stamp.toSec());
  }
  void ReadIndex();
  void Associate(double max_difference_s);
  sensor_msgs::Image::ConstPtr Message(const Topic& topic, size_t k) const;
};

void RosbagReader::Impl::ReadIndex() {
  std::vector<std::string> names;
  for (const Topic& topic : topics) names.push_back(topic.name);
  rosbag::View view(bag, rosbag::TopicQuery(names));
  for (const rosbag::MessageInstance& m : view) {
    Topic& topic = topics[m.getTopic() == topics[0].name ? 0 : 1];
    if (m.getDataType() != "sensor_msgs/Image") {
      ThrowInFile(path, fmt::format("topic {} holds {}, not sensor_msgs/Image", topic.name,
                                    m.getDataType()));
    }
    const sensor_msgs::Image::ConstPtr image = m.instantiate<sensor_msgs::Image>();
    const std::string where = Where(topic, image->header.stamp);
    if (topic.messages.empty()) topic.encoding = image->encoding;
    if (image->encoding != topic.encoding) {
      ThrowInput("{}: encoding {} after {} in the messages before", where, image->encoding,
                 topic.encoding);
    }
    Wrap(*image, where);  // checks the encoding and the sizes now, not in the middle of a run
    topic.messages.push_back({m.getTime(), image->header.stamp});
  }
  for (Topic& topic : topics) {
    if (topic.messages.empty()) {
      rosbag::View all(bag);
      std::string there;
      for (const rosbag::ConnectionInfo* info : all.getConnections()) {
        there += fmt::format("{}{} ({})", there.empty() ? "" : ", ", info->topic, info->datatype);
      }
      ThrowInFile(path, fmt::format("no message on topic {}; the bag has: {}", topic.name,
                                    there.empty() ? "nothing" : there));
    }
    std::stable_sort(topic.messages.begin(), topic.messages.end(),
                     [](const IndexEntry& a, const IndexEntry& b) { return a.stamp < b.stamp; });
  }
}

// Each frame of the first topic takes the nearest unused message of the second within the
// bound; frames with none are left out (as TUM's associate.py leaves them out).
void RosbagReader::Impl::Associate(double max_difference_s) {
  const Topic& first = topics[0];
  std::vector<bool> used(topics.size() == 2 ? topics[1].messages.size() : 0, false);
  for (size_t k = 0; k < first.messages.size(); ++k) {
    const double t = first.messages[k].stamp.toSec();
    if (!frame_messages.empty() && t <= sequence.frames.back().timestamp) {
      spdlog::warn("{}: a second message stamped {:.6f}; the first one is kept",
                   Where(first, first.messages[k].stamp), t);
      continue;
    }
    size_t match = 0;
    if (topics.size() == 2) {
      const std::vector<IndexEntry>& other = topics[1].messages;
      std::optional<size_t> best;
      const auto from = std::lower_bound(
          other.begin(), other.end(), t - max_difference_s,
          [](const IndexEntry& e, double value) { return e.stamp.toSec() < value; });
      for (size_t j = from - other.begin(); j < other.size(); ++j) {  // sorted: stop past the bound
        const double dt = other[j].stamp.toSec() - t;
        if (dt > max_difference_s) break;
        if (!used[j] && std::abs(dt) <= max_difference_s &&
            (!best || std::abs(dt) < std::abs(other[*best].stamp.toSec() - t))) {
          best = j;
        }
      }
      if (!best) continue;
      used[*best] = true;
      match = *best;
    }
    io::FrameEntry frame;
    frame.index = static_cast<int>(sequence.frames.size());
    frame.timestamp = t;
    frame.image_left = path;
    if (sequence.sensor == io::SensorType::kRgbD) frame.depth = path;
    if (sequence.sensor == io::SensorType::kStereo) frame.image_right = path;
    sequence.frames.push_back(frame);
    frame_messages.emplace_back(k, match);
  }
}

sensor_msgs::Image::ConstPtr RosbagReader::Impl::Message(const Topic& topic, size_t k) const {
  const IndexEntry& entry = topic.messages[k];
  rosbag::View view(bag, rosbag::TopicQuery(topic.name), entry.bag_time, entry.bag_time);
  for (const rosbag::MessageInstance& m : view) {
    sensor_msgs::Image::ConstPtr image = m.instantiate<sensor_msgs::Image>();
    if (image != nullptr && image->header.stamp == entry.stamp) return image;
  }
  ThrowInput("{}: the message is no longer in the bag", Where(topic, entry.stamp));
}

RosbagReader::RosbagReader(const std::string& path, const RosbagOptions& options)
    : impl_(std::make_unique<Impl>()) {
  options.Check();
  impl_->path = path;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) ThrowInFile(path, "is a folder, not a bag file");
  if (!std::filesystem::exists(path, ec)) ThrowInFile(path, "no such bag file");
  try {
    impl_->bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    ThrowInFile(path, fmt::format("cannot be read as a ROS 1 bag: {}", e.what()));
  }
  for (const std::string& name : options.topics) impl_->topics.push_back({name, "", {}});
  try {
    impl_->ReadIndex();
  } catch (const rosbag::BagException& e) {
    ThrowInFile(path, fmt::format("broken bag: {}", e.what()));
  } catch (const ros::Exception& e) {
    ThrowInFile(path, fmt::format("a message cannot be read: {}", e.what()));
  }
  const std::vector<Topic>& topics = impl_->topics;
  if (!IsColourEncoding(topics[0].encoding)) {
    ThrowInFile(path, fmt::format("topic {} is {}: the first topic must be an image (rgb8, bgr8, "
                                  "rgba8, bgra8, mono8)",
                                  topics[0].name, topics[0].encoding));
  }
  io::Sequence& sequence = impl_->sequence;
  sequence.name = std::filesystem::path(path).stem().string();
  sequence.root = path;
  sequence.sensor = topics.size() == 1                    ? io::SensorType::kMonocular
                    : IsDepthEncoding(topics[1].encoding) ? io::SensorType::kRgbD
                                                          : io::SensorType::kStereo;
  impl_->Associate(options.max_difference_s);
  if (sequence.frames.empty()) {
    ThrowInFile(path, fmt::format("no message of {} has one of {} within {} s", topics[0].name,
                                  topics[1].name, options.max_difference_s));
  }
  spdlog::info("{}: {} frames from {} ({}){}", path, sequence.size(), topics[0].name,
               topics[0].encoding,
               topics.size() == 2 ? fmt::format(" and {} ({})", topics[1].name, topics[1].encoding)
                                  : std::string());
}

RosbagReader::~RosbagReader() = default;

const io::Sequence& RosbagReader::sequence() const { return impl_->sequence; }

io::FrameImages RosbagReader::Read(int index, io::ColourMode mode) {
  const Impl& impl = *impl_;
  MOSLAM_CHECK(index >= 0 && static_cast<size_t>(index) < impl.frame_messages.size())
      << "frame " << index << " of " << impl.frame_messages.size();
  const auto [k, j] = impl.frame_messages[static_cast<size_t>(index)];
  io::FrameImages images;
  try {
    const Topic& first = impl.topics[0];
    const auto left = impl.Message(first, k);
    images.left =
        ToColourMode(Wrap(*left, impl.Where(first, left->header.stamp)), first.encoding, mode);
    if (impl.topics.size() == 2) {
      const Topic& second = impl.topics[1];
      const auto other = impl.Message(second, j);
      const cv::Mat pixels = Wrap(*other, impl.Where(second, other->header.stamp));
      if (pixels.size() != images.left.size()) {
        ThrowInput("{}: {}x{}, but {} is {}x{}", impl.Where(second, other->header.stamp),
                   pixels.cols, pixels.rows, first.name, images.left.cols, images.left.rows);
      }
      if (impl.sequence.sensor == io::SensorType::kRgbD) {
        images.depth = ToMetres(pixels);
      } else {
        images.right = ToColourMode(pixels, second.encoding, mode);
      }
    }
  } catch (const rosbag::BagException& e) {
    ThrowInFile(impl.path, fmt::format("frame {}: {}", index, e.what()));
  }
  return images;
}

bool RosbagSupported() { return true; }

#else  // !MOSLAM_HAVE_ROSBAG

struct RosbagReader::Impl {};

RosbagReader::RosbagReader(const std::string& path, const RosbagOptions& options) {
  options.Check();
  ThrowInFile(
      path,
      "this moslam was built without librosbag (Debian's librosbag-dev and "
      "libsensor-msgs-dev, which scripts/setup.sh installs); rebuild after installing them");
}
RosbagReader::~RosbagReader() = default;
const io::Sequence& RosbagReader::sequence() const {
  static const io::Sequence none;
  return none;
}
io::FrameImages RosbagReader::Read(int, io::ColourMode) { return {}; }
bool RosbagSupported() { return false; }

#endif

}  // namespace moslam::sensors
