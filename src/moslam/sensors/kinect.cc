#include "moslam/sensors/kinect.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgproc.hpp>

#include "moslam/util/error.h"
#include "moslam/util/strings.h"

#if MOSLAM_HAVE_FREENECT
#include <libfreenect.h>
#include <libfreenect_sync.h>
#endif

namespace moslam::sensors {

int ParseKinectIndex(const std::string& text) {
  const auto index = ParseInt(Trim(text));
  if (!index || *index < 0 || *index > 64) {
    ThrowInput("--dataset kinect: '{}' is no device index (0 for the first Kinect)", text);
  }
  return static_cast<int>(*index);
}

#if MOSLAM_HAVE_FREENECT

namespace {

constexpr int kWidth = 640, kHeight = 480;  // FREENECT_RESOLUTION_MEDIUM, the sync API's

// How many Kinects libfreenect sees, through a context of its own (the sync API keeps another).
int CountDevices(const std::string& name) {
  freenect_context* context = nullptr;
  if (freenect_init(&context, nullptr) < 0 || context == nullptr) {
    ThrowInFile(name,
                "libfreenect cannot start (no USB access: is /dev/bus/usb there and "
                "readable?)");
  }
  freenect_select_subdevices(context, FREENECT_DEVICE_CAMERA);
  const int count = freenect_num_devices(context);
  freenect_shutdown(context);
  return count;
}

class Kinect : public io::LiveSource {
 public:
  explicit Kinect(int index) : index_(index) {}
  // The sync API's thread and the device are released (a later run may open it again).
  ~Kinect() override { freenect_sync_stop(); }

  std::optional<io::LiveFrame> Grab() override {
    void* rgb = nullptr;
    void* depth = nullptr;
    uint32_t rgb_ticks = 0, depth_ticks = 0;
    // Each call waits for the next frame of its stream; both streams run at 30 Hz.
    if (freenect_sync_get_video(&rgb, &rgb_ticks, index_, FREENECT_VIDEO_RGB) != 0 ||
        freenect_sync_get_depth(&depth, &depth_ticks, index_, FREENECT_DEPTH_REGISTERED) != 0) {
      ThrowInFile(name(), "delivered no frame (unplugged?)");
    }
    io::LiveFrame frame;
    last_stamp_ = frame.timestamp = clock_.NextAfter(last_stamp_);
    const cv::Mat rgb_view(kHeight, kWidth, CV_8UC3, rgb);
    cv::cvtColor(rgb_view, frame.images.left, cv::COLOR_RGB2BGR);
    // Registered depth is in millimetres, 0 where there is no measurement.
    const cv::Mat depth_view(kHeight, kWidth, CV_16UC1, depth);
    depth_view.convertTo(frame.images.depth, CV_32F, 1.0 / 1000.0);
    return frame;
  }
  io::SensorType sensor() const override { return io::SensorType::kRgbD; }
  std::string name() const override { return fmt::format("kinect:{}", index_); }
  cv::Size image_size() const override { return {kWidth, kHeight}; }

 private:
  int index_ = 0;
  io::LiveClock clock_;
  double last_stamp_ = 0.0;
};

}  // namespace

bool KinectSupported() { return true; }

std::unique_ptr<io::LiveSource> OpenKinect(int index, const cv::Size& size) {
  const std::string name = fmt::format("kinect:{}", index);
  if (!size.empty() && size != cv::Size(kWidth, kHeight)) {
    ThrowInFile(name, fmt::format("gives {}x{} frames, not the {}x{} of the settings' "
                                  "Camera.width x Camera.height",
                                  kWidth, kHeight, size.width, size.height));
  }
  const int count = CountDevices(name);
  if (index >= count) {
    ThrowInFile(name, fmt::format("no such Kinect v1: libfreenect finds {} (plugged in, powered, "
                                  "and /dev/bus/usb readable?)",
                                  count));
  }
  spdlog::info("{}: Kinect v1, 640x480 colour with registered depth", name);
  return std::make_unique<Kinect>(index);
}

#else  // !MOSLAM_HAVE_FREENECT

bool KinectSupported() { return false; }

std::unique_ptr<io::LiveSource> OpenKinect(int index, const cv::Size&) {
  ThrowInFile(fmt::format("kinect:{}", index),
              "this moslam was built without libfreenect (Debian's libfreenect-dev, which "
              "scripts/setup.sh installs); rebuild after installing it");
}

#endif

}  // namespace moslam::sensors
