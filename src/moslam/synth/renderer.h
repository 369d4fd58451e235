// Off-screen OpenGL renderer of textured boxes and triangle meshes through OSMesa (Mesa's llvmpipe
// software rasterizer).
//
// Why OSMesa rather than a ray caster of our own: llvmpipe is a complete, multithreaded GL 3.3+
// implementation shipped by Debian (libosmesa6-dev), so we get mipmapped trilinear
// texture filtering (clean multi-scale texture for ORB's pyramid), depth testing and several
// render targets for free, at hundreds of frames per second for scenes of a few hundred boxes.
// A ray caster would need all of that written and tuned by hand. EGL's surfaceless platform
// would work too but needs more setup for the same llvmpipe back end.
//
// One render gives, per pixel: colour, exact metric depth (camera z, written by the fragment
// shader, not recovered from the non-linear depth buffer), class id and instance id.
//
// Determinism: llvmpipe rasterizes fixed screen tiles in its threads, so output does not depend on
// thread scheduling; LP_NUM_THREADS is set (when unset) before the context is made so the set-up
// is always the same. A test checks byte-identical output.
#pragma once

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/geometry/se3.h"
#include "moslam/synth/scene.h"
#include "moslam/synth/texture.h"

namespace moslam::synth {

struct RenderOutput {
  cv::Mat rgb;       // CV_8UC3, RGB order
  cv::Mat depth;     // CV_32FC1, camera z in metres; 0 where nothing was hit (sky)
  cv::Mat class_id;  // CV_8UC1
  cv::Mat instance;  // CV_16UC1
};

struct Lighting {
  Eigen::Vector3d direction_world = Eigen::Vector3d(0.4, -0.3, -0.86);  // light travels along this
  float ambient = 0.55f;
  float diffuse = 0.5f;
  Eigen::Vector3d sky_rgb = Eigen::Vector3d(0.62, 0.74, 0.9);  // where nothing is hit, [0, 1]
};

class Renderer {
 public:
  // Creates a GL 3.3 core context of width x height and uploads every texture (mipmapped).
  // Throws std::runtime_error when OSMesa cannot create the context.
  Renderer(int width, int height, const TextureSet& textures);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  int width() const;
  int height() const;

  // Renders `boxes` seen by a pinhole camera (intrinsics of `camera`; its size must equal the
  // renderer's) at T_cam_world (OpenCV camera axes: x right, y down, z forward).
  void Render(const std::vector<Box>& boxes, const camera::PinholeOptions& camera,
              const geometry::SE3& T_cam_world, const Lighting& lighting, RenderOutput* out);
  // ... and triangle meshes in world coordinates (skinned people, body.h).
  void Render(const std::vector<Box>& boxes, const std::vector<Mesh>& meshes,
              const camera::PinholeOptions& camera, const geometry::SE3& T_cam_world,
              const Lighting& lighting, RenderOutput* out);

  // "llvmpipe (LLVM 15.0.6) ..." for logs.
  std::string RendererName() const;

 private:
  void DrawMeshes(const std::vector<Mesh>& meshes);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace moslam::synth
