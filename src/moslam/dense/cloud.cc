#include "moslam/dense/cloud.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>

#include <opencv2/imgproc.hpp>

#include "moslam/util/atomic_file.h"
#include "moslam/util/error.h"

namespace moslam::dense {

std::string PlyBytes(const std::vector<Voxel>& voxels) {
  std::string out =
      "ply\nformat binary_little_endian 1.0\ncomment moslam dense map: occupied voxel centres\n"
      "element vertex " +
      std::to_string(voxels.size()) +
      "\nproperty float x\nproperty float y\nproperty float z\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  const size_t header = out.size();
  constexpr size_t kVertexBytes = 3 * sizeof(float) + 3;
  out.resize(header + voxels.size() * kVertexBytes);
  char* p = out.data() + header;
  // x86-64 and every platform Debian 12 builds moslam for are little-endian; the copy is the
  // file's byte order.
  static_assert(sizeof(float) == 4, "PLY floats are 4 bytes");
  for (const Voxel& v : voxels) {
    std::memcpy(p, v.centre.data(), 3 * sizeof(float));
    p += 3 * sizeof(float);
    *p++ = static_cast<char>(v.r);
    *p++ = static_cast<char>(v.g);
    *p++ = static_cast<char>(v.b);
  }
  return out;
}

void WritePly(const std::vector<Voxel>& voxels, const std::string& path) {
  WriteFileAtomically(path, PlyBytes(voxels), "point cloud");
}

void RenderOptions::Check() const {
  if (width < 16 || width > 16384) {
    throw InputError("RenderOptions.width must be 16..16384 pixels, got " + std::to_string(width));
  }
  if (up_axis < 0 || up_axis > 2) {
    throw InputError("RenderOptions.up_axis must be 0, 1 or 2, got " + std::to_string(up_axis));
  }
}

namespace {

void DrawScaleBar(cv::Mat* image, double pixels_per_metre) {
  const int length = static_cast<int>(std::lround(pixels_per_metre));
  const cv::Point a(10, image->rows - 12), b(10 + length, image->rows - 12);
  cv::line(*image, a, b, cv::Scalar(0, 0, 0), 2);
  cv::putText(*image, "1 m", cv::Point(14 + length, image->rows - 7), cv::FONT_HERSHEY_SIMPLEX,
              0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
}

}  // namespace

cv::Mat RenderTopView(const std::vector<Voxel>& voxels, double resolution,
                      const RenderOptions& options) {
  options.Check();
  if (voxels.empty())
    return cv::Mat(options.width / 2, options.width, CV_8UC3, cv::Scalar::all(255));
  const int h = options.up_axis, a0 = h == 0 ? 1 : 0, a1 = 3 - h - a0;
  Eigen::Vector3f lo = voxels.front().centre, hi = lo;
  for (const Voxel& v : voxels) {
    lo = lo.cwiseMin(v.centre);
    hi = hi.cwiseMax(v.centre);
  }
  const double margin = 4.0 * resolution;
  const double extent0 = hi[a0] - lo[a0] + 2 * margin, extent1 = hi[a1] - lo[a1] + 2 * margin;
  const double ppm = options.width / extent0;  // pixels per metre
  const int height = std::clamp(static_cast<int>(std::ceil(extent1 * ppm)) + 24, 16, 16384);
  cv::Mat image(height, options.width, CV_8UC3, cv::Scalar::all(255));
  // Height above the lowest voxel: drawn lowest first, so what is on top stays visible.
  const auto height_of = [&](const Voxel& v) {
    return options.up_positive ? v.centre[h] - lo[h] : hi[h] - v.centre[h];
  };
  std::vector<size_t> order(voxels.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t i, size_t j) { return height_of(voxels[i]) < height_of(voxels[j]); });
  // One pixel more than a voxel spans: truncated positions otherwise leave seams between voxels.
  const int side = static_cast<int>(std::ceil(resolution * ppm)) + 1;
  const double span = std::max(1e-6, static_cast<double>(hi[h] - lo[h]));
  for (size_t i : order) {
    const Voxel& v = voxels[i];
    const int u = static_cast<int>((v.centre[a0] - lo[a0] + margin) * ppm);
    // Image rows run against a1, so that a1 (z: the first camera's forward) points up.
    const int r = static_cast<int>((hi[a1] - v.centre[a1] + margin) * ppm);
    const double shade = 0.55 + 0.45 * height_of(v) / span;  // higher is brighter
    const cv::Scalar colour(v.b * shade, v.g * shade, v.r * shade);
    cv::rectangle(image, cv::Rect(u - side / 2, r - side / 2, side, side), colour, cv::FILLED);
  }
  DrawScaleBar(&image, ppm);
  return image;
}

}  // namespace moslam::dense
