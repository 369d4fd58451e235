#include "moslam/viewer/message.h"

#include <cmath>
#include <cstring>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace moslam::viewer {
namespace {

void Pad4(std::string* out) {
  while (out->size() % 4 != 0) out->push_back('\0');
}

template <typename T>
std::string Bytes(const std::vector<T>& values) {
  return std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

std::vector<float> KeyframePoses(const std::vector<geometry::SE3>& poses) {
  std::vector<float> out;
  out.reserve(12 * poses.size());
  for (const geometry::SE3& T : poses) {
    const Eigen::Matrix3d R = T.rotation_matrix();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) out.push_back(static_cast<float>(R(r, c)));
    }
    for (int r = 0; r < 3; ++r) out.push_back(static_cast<float>(T.translation()(r)));
  }
  return out;
}

cv::Mat Shrunk(const cv::Mat& image, int max_width, double* scale) {
  cv::Mat out = image;
  *scale = 1.0;
  while (max_width > 0 && out.cols > max_width) {
    cv::resize(out, out, cv::Size(out.cols / 2, out.rows / 2), 0, 0, cv::INTER_AREA);
    *scale *= 0.5;
  }
  return out;
}

std::string Encoded(const std::string& ext, const cv::Mat& image) {
  std::vector<uint8_t> buffer;
  std::vector<int> params;
  if (ext == ".jpg") params = {cv::IMWRITE_JPEG_QUALITY, 80};
  cv::imencode(ext, image, buffer, params);
  return Bytes(buffer);
}

}  // namespace

std::string EncodeSnapshot(const Snapshot& snapshot, const RunPicture& picture,
                           int max_image_width) {
  std::vector<std::pair<std::string, std::string>> sections;
  nlohmann::json header = snapshot.numbers;
  if (snapshot.view) {
    const slam::SystemView& v = *snapshot.view;
    sections.emplace_back("points", Bytes(v.points));
    sections.emplace_back("point_states", Bytes(v.point_states));
    sections.emplace_back("keyframes", Bytes(KeyframePoses(v.keyframes)));
    sections.emplace_back("keypoints", Bytes(v.keypoints));
    sections.emplace_back("keypoint_kinds", Bytes(v.keypoint_kinds));
  }
  sections.emplace_back("trajectory", Bytes(picture.trajectory));
  sections.emplace_back("ground_truth", Bytes(picture.ground_truth));
  if (snapshot.T_world_cam)
    sections.emplace_back("camera", Bytes(KeyframePoses({*snapshot.T_world_cam})));
  if (!snapshot.image.empty()) {
    double scale = 1.0;
    const cv::Mat image = Shrunk(snapshot.image, max_image_width, &scale);
    header["image_scale"] = scale;  // keypoints are in full-size pixels
    header["image_width"] = snapshot.image.cols;
    header["image_height"] = snapshot.image.rows;
    sections.emplace_back("image", Encoded(".jpg", image));
    if (!snapshot.mask.empty()) {
      double mask_scale = 1.0;
      cv::Mat mask = Shrunk(snapshot.mask, max_image_width, &mask_scale);
      cv::threshold(mask, mask, 0, 255, cv::THRESH_BINARY);
      sections.emplace_back("mask", Encoded(".png", mask));
    }
  }
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [name, bytes] : sections)
    list.push_back({{"name", name}, {"bytes", bytes.size()}});
  header["sections"] = list;
  const std::string json = header.dump();
  std::string out = "MSV1";
  const uint32_t n = static_cast<uint32_t>(json.size());
  out.append(reinterpret_cast<const char*>(&n), 4);
  out += json;
  Pad4(&out);
  for (const auto& [name, bytes] : sections) {
    out += bytes;
    Pad4(&out);
  }
  return out;
}

std::vector<float> AlignGroundTruth(const eval::Trajectory& gt, double t0,
                                    const geometry::SE3& T_world_cam0, double until) {
  std::vector<float> out;
  if (gt.empty() || !gt.has_timestamps()) return out;
  size_t nearest = 0;
  for (size_t i = 1; i < gt.size(); ++i) {
    if (std::abs(gt.timestamps[i] - t0) < std::abs(gt.timestamps[nearest] - t0)) nearest = i;
  }
  const geometry::SE3 T_align = T_world_cam0 * gt.poses[nearest].Inverse();
  // From the first tracked frame on: the frames before it have no estimate to compare with.
  for (size_t i = nearest; i < gt.size() && gt.timestamps[i] <= until + 1e-6; ++i) {
    const Eigen::Vector3d p = T_align * gt.poses[i].translation();
    out.insert(out.end(),
               {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
  }
  return out;
}

const std::string* DecodedMessage::Section(const std::string& name) const {
  for (const auto& [n, bytes] : sections) {
    if (n == name) return &bytes;
  }
  return nullptr;
}

std::optional<DecodedMessage> DecodeMessage(const std::string& bytes) {
  if (bytes.size() < 8 || bytes.compare(0, 4, "MSV1") != 0) return std::nullopt;
  uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 4, 4);
  if (8 + static_cast<size_t>(n) > bytes.size()) return std::nullopt;
  DecodedMessage message;
  message.header = nlohmann::json::parse(bytes.substr(8, n), nullptr, false);
  if (message.header.is_discarded() || !message.header.contains("sections")) return std::nullopt;
  size_t at = (8 + n + 3) / 4 * 4;
  for (const auto& section : message.header["sections"]) {
    const size_t size = section.value("bytes", size_t{0});
    if (at + size > bytes.size()) return std::nullopt;
    message.sections.emplace_back(section.value("name", ""), bytes.substr(at, size));
    at = (at + size + 3) / 4 * 4;
  }
  return message;
}

}  // namespace moslam::viewer
