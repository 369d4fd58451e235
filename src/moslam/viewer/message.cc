#include "moslam/viewer/message.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/util/check.h"

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

// Covisibility edges (i, j, weight, both directions) once each: i < j, as the page draws them.
std::vector<uint32_t> OneWay(const std::vector<uint32_t>& edges) {
  std::vector<uint32_t> out;
  out.reserve(edges.size() / 2 + 3);
  for (size_t k = 0; k + 2 < edges.size(); k += 3) {
    if (edges[k] < edges[k + 1]) out.insert(out.end(), {edges[k], edges[k + 1], edges[k + 2]});
  }
  return out;
}

}  // namespace

cv::Mat ColourDepth(const cv::Mat& depth, float* far_m) {
  MOSLAM_CHECK(depth.type() == CV_32FC1);
  const cv::Mat valid = depth > 0;
  if (*far_m <= 0.0f) {
    std::vector<float> values;
    values.reserve(depth.total());
    for (int r = 0; r < depth.rows; ++r) {
      const float* row = depth.ptr<float>(r);
      for (int c = 0; c < depth.cols; ++c) {
        if (row[c] > 0 && std::isfinite(row[c])) values.push_back(row[c]);
      }
    }
    if (!values.empty()) {
      const auto at = values.begin() + static_cast<std::ptrdiff_t>(0.98 * (values.size() - 1));
      std::nth_element(values.begin(), at, values.end());
      *far_m = *at;
    }
    if (*far_m <= 0.0f) *far_m = 1.0f;
  }
  cv::Mat grey, colour;
  depth.convertTo(grey, CV_8U, 255.0 / *far_m);  // saturates beyond far_m
  cv::applyColorMap(grey, colour, cv::COLORMAP_TURBO);
  colour.setTo(cv::Scalar::all(0), ~valid);
  return colour;
}

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
    if (!v.rejected_keypoints.empty())
      sections.emplace_back("rejected_keypoints", Bytes(v.rejected_keypoints));
    if (!v.loops.empty()) sections.emplace_back("loops", Bytes(v.loops));
    if (v.has_graph) {
      sections.emplace_back("covisibility", Bytes(OneWay(v.covisibility)));
      sections.emplace_back("spanning_tree", Bytes(v.spanning_tree));
    }
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
  if (!snapshot.depth.empty()) {
    cv::Mat depth = snapshot.depth;
    // Nearest, not area: averaging a valid depth with a missing one (0) would invent depths.
    while (depth.cols > max_image_width / 2 && depth.cols >= 2) {
      cv::resize(depth, depth, cv::Size(depth.cols / 2, depth.rows / 2), 0, 0, cv::INTER_NEAREST);
    }
    float far_m = 0.0f;
    sections.emplace_back("depth", Encoded(".jpg", ColourDepth(depth, &far_m)));
    header["depth_far_m"] = far_m;
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
