// What the viewer page is sent (web/viewer.js reads it): one binary WebSocket message per update,
//   "MSV1", u32 n, n bytes of JSON (the numbers and the list of sections), padding to 4 bytes,
//   then each section of the list in order, each padded to 4 bytes;
// sections: float32, uint32 or uint8 arrays (points, states, keyframe poses, keypoints, keypoints
// the mask took away, keyframe edges, trajectories), the current image (JPEG), its movable mask
// (PNG) and, when the page asks, its depth (colour-mapped JPEG). A section the snapshot has no
// data for is left out: the keyframe graph and the depth cost nothing until asked for.
// Little-endian, as every browser's typed arrays on the machines this runs on.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "moslam/eval/trajectory.h"
#include "moslam/geometry/se3.h"
#include "moslam/slam/system.h"

namespace moslam::viewer {

// One update as the tracking thread hands it over: cheap to make (the images are shared, not
// copied; the map is copied only when someone watches), encoded in the server thread.
struct Snapshot {
  nlohmann::json numbers;  // frame, state, frames/s, stage times, counts (LiveViewer::Numbers)
  std::optional<slam::SystemView> view;  // nullopt: the tracker has none (runner::Tracker::View)
  cv::Mat image;                         // the frame as tracked (grey or colour); empty: none
  cv::Mat mask;                          // CV_8UC1 movable mask; empty: none
  cv::Mat depth;  // CV_32FC1 metres (0: none), only while the page shows depth; empty: none
  // Camera positions (x, y, z per frame with a pose) since the previous snapshot, and the current
  // pose (none while lost).
  std::vector<float> new_trajectory;
  std::optional<geometry::SE3> T_world_cam;
  // The first tracked frame's time and pose, where the ground truth is aligned (AlignGroundTruth).
  std::optional<std::pair<double, geometry::SE3>> first_pose;
};

// The server thread's view of the whole run, to which each snapshot adds.
struct RunPicture {
  std::vector<float> trajectory;    // x, y, z per tracked frame
  std::vector<float> ground_truth;  // x, y, z, in the estimate's frame (AlignGroundTruth)
};

// Encodes `snapshot` with the whole trajectory so far; images wider than `max_image_width` are
// halved until they fit (the page shows them in a corner), the depth until it is at most half
// that wide.
std::string EncodeSnapshot(const Snapshot& snapshot, const RunPicture& picture,
                           int max_image_width = 640);

// A depth map (CV_32FC1 metres, 0 = none) as a colour picture (CV_8UC3): near blue to far red
// (OpenCV's turbo map) from 0 to `far_m`, pixels without depth black. `far_m` <= 0: the 98th
// percentile of the valid depths, so that a few far pixels do not wash the picture out.
cv::Mat ColourDepth(const cv::Mat& depth, float* far_m);

// The ground truth's positions (x, y, z) from time `t0` up to time `until`, moved so that its pose
// nearest in time to `t0` lies on the estimate's pose then, `T_world_cam0`: the two start together
// and drift apart as the estimate does. Empty for a ground truth without timestamps.
std::vector<float> AlignGroundTruth(const eval::Trajectory& gt, double t0,
                                    const geometry::SE3& T_world_cam0, double until);

// A decoded message (tests, and the benchmark's checks): the JSON and each section's bytes.
struct DecodedMessage {
  nlohmann::json header;
  std::vector<std::pair<std::string, std::string>> sections;  // name, bytes
  const std::string* Section(const std::string& name) const;
};
// nullopt when `bytes` is not a well-formed message.
std::optional<DecodedMessage> DecodeMessage(const std::string& bytes);

}  // namespace moslam::viewer
