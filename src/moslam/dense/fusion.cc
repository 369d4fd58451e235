#include "moslam/dense/fusion.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include <octomap/ColorOcTree.h>
#include <opencv2/imgproc.hpp>

#include "moslam/util/error.h"

namespace moslam::dense {

void DenseFusionOptions::Check() const {
  if (!(resolution > 0.0) || !std::isfinite(resolution)) {
    throw InputError("DenseFusionOptions.resolution must be > 0 metres, got " +
                     std::to_string(resolution));
  }
  if (pixel_step < 1) {
    throw InputError("DenseFusionOptions.pixel_step must be >= 1, got " +
                     std::to_string(pixel_step));
  }
  if (!(min_depth >= 0.0) || !std::isfinite(min_depth)) {
    throw InputError("DenseFusionOptions.min_depth must be >= 0 metres, got " +
                     std::to_string(min_depth));
  }
  if (!(max_depth > min_depth) || !std::isfinite(max_depth)) {
    throw InputError("DenseFusionOptions.max_depth must be > min_depth (" +
                     std::to_string(min_depth) + " m), got " + std::to_string(max_depth));
  }
  if (mask_margin_px < 0) {
    throw InputError("DenseFusionOptions.mask_margin_px must be >= 0, got " +
                     std::to_string(mask_margin_px));
  }
}

namespace {

void CheckView(const DepthView& view) {
  if (view.depth.empty() || view.depth.type() != CV_32FC1) {
    throw InputError("dense fusion: the depth image must be CV_32FC1 metres");
  }
  const auto same_size = [&](const cv::Mat& m) { return m.size() == view.depth.size(); };
  if (!view.colour.empty() && (view.colour.type() != CV_8UC3 || !same_size(view.colour))) {
    throw InputError("dense fusion: the colour image must be CV_8UC3 of the depth's size " +
                     std::to_string(view.depth.cols) + "x" + std::to_string(view.depth.rows));
  }
  if (!view.mask.empty() && (view.mask.type() != CV_8UC1 || !same_size(view.mask))) {
    throw InputError("dense fusion: the mask must be CV_8UC1 of the depth's size " +
                     std::to_string(view.depth.cols) + "x" + std::to_string(view.depth.rows));
  }
}

// The mask the pixels are tested against: grown by the margin when masked pixels are left out
// (the outline of a body mixes its depth with the background's), as it is when only masked pixels
// are wanted.
cv::Mat MaskFor(const DepthView& view, const DenseFusionOptions& options, MaskUse use) {
  if (view.mask.empty() || use == MaskUse::kOnly || options.mask_margin_px == 0) return view.mask;
  cv::Mat grown;
  const int size = 2 * options.mask_margin_px + 1;
  cv::dilate(view.mask, grown, cv::getStructuringElement(cv::MORPH_ELLIPSE, {size, size}));
  return grown;
}

}  // namespace

std::vector<Eigen::Vector3d> BackProject(const Intrinsics& in, const DenseFusionOptions& options,
                                         const DepthView& view, MaskUse use,
                                         std::vector<cv::Vec3b>* colours, InsertStats* stats) {
  CheckView(view);
  const cv::Mat mask = MaskFor(view, options, use);
  if (use == MaskUse::kOnly && mask.empty()) return {};
  const Eigen::Matrix3d R = view.T_world_cam.rotation_matrix();
  const Eigen::Vector3d t = view.T_world_cam.translation();
  std::vector<Eigen::Vector3d> points;
  InsertStats counts;
  for (int v = options.pixel_step / 2; v < view.depth.rows; v += options.pixel_step) {
    const float* depth_row = view.depth.ptr<float>(v);
    const uint8_t* mask_row = mask.empty() ? nullptr : mask.ptr<uint8_t>(v);
    for (int u = options.pixel_step / 2; u < view.depth.cols; u += options.pixel_step) {
      const double z = depth_row[u];
      if (!std::isfinite(z) || z <= options.min_depth || z > options.max_depth) {
        ++counts.invalid;
        continue;
      }
      const bool masked = mask_row != nullptr && mask_row[u] != 0;
      if (masked != (use == MaskUse::kOnly)) {
        if (masked) ++counts.masked;
        continue;
      }
      const Eigen::Vector3d p_cam((u - in.cx) * z / in.fx, (v - in.cy) * z / in.fy, z);
      points.push_back(R * p_cam + t);
      if (colours) {
        colours->push_back(view.colour.empty() ? cv::Vec3b(128, 128, 128)
                                               : view.colour.at<cv::Vec3b>(v, u));
      }
      ++counts.rays;
    }
  }
  if (stats) *stats = counts;
  return points;
}

DenseFusion::DenseFusion(const Intrinsics& intrinsics, const DenseFusionOptions& options)
    : intrinsics_(intrinsics), options_(options) {
  options_.Check();
  if (!(intrinsics.fx > 0.0) || !(intrinsics.fy > 0.0)) {
    throw InputError("dense fusion: the focal lengths must be > 0 pixels");
  }
  tree_ = std::make_unique<octomap::ColorOcTree>(options_.resolution);
}

DenseFusion::~DenseFusion() = default;

InsertStats DenseFusion::Insert(const DepthView& view) {
  InsertStats stats;
  std::vector<cv::Vec3b> colours;
  const std::vector<Eigen::Vector3d> points =
      BackProject(intrinsics_, options_, view, MaskUse::kLeaveOut, &colours, &stats);
  octomap::Pointcloud cloud;
  cloud.reserve(points.size());
  for (const Eigen::Vector3d& p : points) cloud.push_back(p.x(), p.y(), p.z());
  const Eigen::Vector3d o = view.T_world_cam.translation();
  const octomap::point3d origin(static_cast<float>(o.x()), static_cast<float>(o.y()),
                                static_cast<float>(o.z()));
  if (options_.ray_casting) {
    // discretize: one ray per end voxel (many pixels end in the same 5 cm voxel at short range),
    // which changes no endpoint and saves most of the ray casting.
    tree_->insertPointCloud(cloud, origin, -1.0, /*lazy_eval=*/false, /*discretize=*/true);
  } else {
    for (const Eigen::Vector3d& p : points) {
      tree_->updateNode(static_cast<float>(p.x()), static_cast<float>(p.y()),
                        static_cast<float>(p.z()), true);
    }
  }
  for (size_t i = 0; i < points.size(); ++i) {
    const cv::Vec3b& bgr = colours[i];
    tree_->integrateNodeColor(static_cast<float>(points[i].x()), static_cast<float>(points[i].y()),
                              static_cast<float>(points[i].z()), bgr[2], bgr[1], bgr[0]);
  }
  return stats;
}

std::vector<Voxel> DenseFusion::OccupiedVoxels() const {
  std::vector<std::pair<octomap::OcTreeKey, Voxel>> keyed;
  for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it) {
    if (!tree_->isNodeOccupied(*it)) continue;
    // Leaves are pruned into larger cubes where all children agree; a larger leaf stands for
    // every finest voxel inside it.
    const double size = it.getSize();
    const int n = static_cast<int>(std::lround(size / options_.resolution));
    const octomap::point3d c = it.getCoordinate();
    const octomap::ColorOcTreeNode::Color color = it->getColor();
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        for (int k = 0; k < n; ++k) {
          Voxel v;
          v.centre =
              Eigen::Vector3f(c.x(), c.y(), c.z()) +
              static_cast<float>(options_.resolution) *
                  Eigen::Vector3f(i - 0.5f * (n - 1), j - 0.5f * (n - 1), k - 0.5f * (n - 1));
          v.r = color.r;
          v.g = color.g;
          v.b = color.b;
          keyed.emplace_back(tree_->coordToKey(v.centre.x(), v.centre.y(), v.centre.z()), v);
        }
      }
    }
  }
  std::sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) {
    return std::tie(a.first[0], a.first[1], a.first[2]) <
           std::tie(b.first[0], b.first[1], b.first[2]);
  });
  std::vector<Voxel> voxels;
  voxels.reserve(keyed.size());
  for (const auto& [key, voxel] : keyed) voxels.push_back(voxel);
  return voxels;
}

size_t DenseFusion::NumOccupied() const {
  size_t count = 0;
  for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it) {
    if (!tree_->isNodeOccupied(*it)) continue;
    const auto n = static_cast<size_t>(std::lround(it.getSize() / options_.resolution));
    count += n * n * n;
  }
  return count;
}

void DenseFusion::WriteBinary(const std::string& path) const {
  // The const writer: the tree is written as it is, not pruned first.
  if (!tree_->writeBinaryConst(path)) throw InputError("cannot write the octree " + path);
}

}  // namespace moslam::dense
