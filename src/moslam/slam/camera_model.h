// The optimizer's plain camera (optim::CameraModel: intrinsics and stereo bf) from the camera
// the SLAM modules are built with; one place for the copy that tracking, local mapping and loop
// closing each need.
#pragma once

#include "moslam/camera/pinhole_camera.h"
#include "moslam/optim/observation.h"

namespace moslam::slam {

// bf: baseline * fx in pixel-metres (settings' Camera.bf); 0 for monocular.
inline optim::CameraModel CameraModelFor(const camera::PinholeCamera& camera, double bf = 0.0) {
  optim::CameraModel model;
  model.fx = camera.fx();
  model.fy = camera.fy();
  model.cx = camera.cx();
  model.cy = camera.cy();
  model.bf = bf;
  return model;
}

}  // namespace moslam::slam
