// Presets: the scenes and camera paths that stand in for the TUM RGB-D dynamic sequences
// (fr3 walking_xyz / static / rpy / halfsphere, sitting_static; Sturm et al., IROS 2012) and a
// KITTI-like street with cars (Geiger et al., CVPR 2012).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/geometry/se3.h"
#include "moslam/synth/renderer.h"
#include "moslam/synth/scene.h"
#include "moslam/synth/texture.h"

namespace moslam::synth {

struct PresetInfo {
  std::string name;
  std::string description;
  bool stereo = false;     // KITTI stereo layout instead of TUM RGB-D
  int default_frames = 0;  // like the TUM / KITTI sequence it mimics
  double rate_hz = 30.0;
};

// Every preset, in a fixed order.
const std::vector<PresetInfo>& Presets();
// Throws InputError naming the known presets when `name` is not one.
const PresetInfo& FindPreset(const std::string& name);

// A sequence to render: a world, a camera path and the camera.
struct SequenceSpec {
  PresetInfo info;
  World world;
  Lighting lighting;
  camera::PinholeOptions camera;                     // the (left) camera
  double baseline_m = 0.0;                           // stereo only
  std::function<geometry::SE3(double)> T_world_cam;  // camera pose at time t (seconds from start)
};

// The TUM fr3 Kinect (640x480, fx 535.4, fy 539.2, cx 320.1, cy 247.6) scaled to width x height.
camera::PinholeOptions TumCamera(int width, int height);
// KITTI 04-12's left grey camera (1226x370, fx 707.0912) scaled to width x height.
camera::PinholeOptions KittiCamera(int width, int height);

// Builds preset `name` with `seed`. Texture indices refer to `textures`. width/height: image size
// (0: the preset's own). `people`: how its people are drawn; the scene, the paths and the camera
// are the same either way (bodies draw their looks from a stream of their own).
SequenceSpec MakePreset(const std::string& name, uint64_t seed, const TextureSet& textures,
                        int width = 0, int height = 0, PeopleStyle people = PeopleStyle::kBoxes);

// One random indoor scene and view for the training mode: a random room, furniture, 0-3 people
// (walking or seated, random gait phase) and a random viewpoint. Seeds are mixed with a stream
// the presets never use, so training scenes are disjoint from benchmark scenes.
SequenceSpec MakeTrainingScene(uint64_t seed, const TextureSet& textures, int width, int height,
                               PeopleStyle people = PeopleStyle::kBoxes);

}  // namespace moslam::synth
