// The sampling pattern of steered BRIEF in ORB (Rublee et al. 2011): 256 point pairs in a 31x31
// patch centred on the keypoint, chosen by the authors' greedy search for uncorrelated,
// high-variance binary tests. It is the published constant of the original ORB implementation
// (OpenCV's bit_pattern_31_, also used by ORB-SLAM2), so that descriptors are interchangeable
// with those of ORB-SLAM2 and its vocabularies.
#pragma once

#include <cstdint>

namespace moslam::feature {

// Row i is bit i of the descriptor: {x1, y1, x2, y2} in pixels, each in [-13, 12]. The bit is 1
// when the smoothed intensity at (x1, y1) is below the one at (x2, y2), after both points are
// rotated by the keypoint's angle.
extern const int8_t kOrbPattern[256][4];

}  // namespace moslam::feature
