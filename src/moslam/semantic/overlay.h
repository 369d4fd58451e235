// Pictures of segmentations for people: label colours blended over the image with boundaries
// drawn, and panels side by side (e.g. before and after the CRF).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace moslam::semantic {

// A fixed, distinguishable BGR colour for each label (label 0 is dark grey).
cv::Scalar LabelColour(int label);

// image (8UC3 or 8UC1) with each pixel tinted by its label's colour (alpha: the colour's share)
// and a 1-pixel line where the label changes. labels: CV_8U of the image's size.
cv::Mat DrawLabelOverlay(const cv::Mat& image, const cv::Mat& labels, double alpha = 0.45);

// image with the pixels of `mask` (CV_8U, nonzero = in) tinted by `colour` and the mask's
// outline drawn in it.
cv::Mat DrawMaskOverlay(const cv::Mat& image, const cv::Mat& mask, const cv::Scalar& colour,
                        double alpha = 0.35);

// The panels (8UC3, same height) left to right, each with its title written at the top left.
cv::Mat SideBySide(const std::vector<cv::Mat>& panels, const std::vector<std::string>& titles);

}  // namespace moslam::semantic
