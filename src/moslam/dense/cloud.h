// Outputs of a dense map besides the octree: a coloured point cloud (PLY, Turk 1994; read by
// MeshLab, CloudCompare, Open3D) and pictures of it rendered by moslam itself, so that a run's
// folder shows its map without another program.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/dense/fusion.h"

namespace moslam::dense {

// Binary little-endian PLY, one vertex per voxel centre (float x y z, uchar red green blue),
// written whole or not at all. InputError naming the file when it cannot be written.
void WritePly(const std::vector<Voxel>& voxels, const std::string& path);
// The PLY's bytes (what WritePly writes).
std::string PlyBytes(const std::vector<Voxel>& voxels);

struct RenderOptions {
  int width = 960;  // pixels of the picture (> 0); the height follows the map's extent
  // The map's vertical axis (0, 1, 2 = x, y, z) and its upward sign: the picture looks down it.
  // The default suits a map in the first camera's frame (y points down). `moslam map export`
  // sets them from the keyframes' orientations (their image's up direction, on average).
  int up_axis = 1;
  bool up_positive = false;
  void Check() const;  // InputError naming the field
};

// An orthographic view of the voxels along `up_axis`, each drawn as a square of its colour
// (shaded by height, so that floors and table tops read apart), with a 1 m scale bar. Empty
// voxels: a blank picture of the given width.
cv::Mat RenderTopView(const std::vector<Voxel>& voxels, double resolution,
                      const RenderOptions& options = {});

}  // namespace moslam::dense
