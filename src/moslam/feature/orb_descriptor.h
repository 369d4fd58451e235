// The two per-keypoint steps of ORB (Rublee et al. 2011): orientation by the intensity centroid
// of a circular patch (Rosin 1999), and the 256-bit steered BRIEF descriptor.
#pragma once

#include <array>
#include <cstdint>

#include <opencv2/core.hpp>

namespace moslam::feature {

// ORB's patch: 31x31 pixels, the size of the descriptor's sampling area.
constexpr int kOrbPatchSize = 31;
constexpr int kOrbHalfPatch = kOrbPatchSize / 2;  // 15
// Bytes of a descriptor (256 bits).
constexpr int kOrbDescriptorBytes = 32;
// Keypoints must lie at least this far (pixels of their level) from the level image border, so
// that the circular patch and the rotated sampling pattern (|x|, |y| <= 13, so radius <= 18.4)
// stay inside the image. Same value as ORB-SLAM2's EDGE_THRESHOLD.
constexpr int kOrbEdgeMargin = 19;

// Half-widths of the rows of the circular patch: row v (0..15) spans u in [-w[v], w[v]]. The
// disk is {u^2 + v^2 <= r(r + 1)} with r = 15, which is symmetric under swapping u and v (so a
// rotated patch covers the same pixels) and equals the table of the original ORB.
std::array<int, kOrbHalfPatch + 1> CircularPatchHalfWidths();

// Orientation in degrees, [0, 360), of the vector from the keypoint to the intensity centroid of
// the circular patch (CircularPatchHalfWidths) around pixel (x, y): atan2(m01, m10) of the
// moments m_pq = sum u^p v^q I(x + u, y + v), with v pointing down the image. `image` is CV_8UC1
// and (x, y) at least kOrbHalfPatch + 1 pixels from its border (rows are read 32 pixels wide).
float IntensityCentroidAngle(const cv::Mat& image, int x, int y);

// Steered BRIEF: the kOrbPattern tests rotated by `angle_deg` around pixel (x, y) of the smoothed
// level image (CV_8UC1; ORB smooths with a 7x7 Gaussian, sigma 2), written to
// descriptor[0..31]. Bit j of byte i is test 8 i + j, as in OpenCV and ORB-SLAM2, so that
// descriptors can be compared with theirs.
void SteeredBrief(const cv::Mat& smoothed, int x, int y, float angle_deg, uint8_t* descriptor);

}  // namespace moslam::feature
