#include "moslam/semantic/overlay.h"

#include <opencv2/imgproc.hpp>

#include "moslam/util/check.h"

namespace moslam::semantic {
namespace {

cv::Mat ToBgr(const cv::Mat& image) {
  MOSLAM_CHECK(image.type() == CV_8UC3 || image.type() == CV_8UC1) << "type " << image.type();
  if (image.channels() == 3) return image.clone();
  cv::Mat bgr;
  cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

// Pixels whose right or lower neighbour has another label.
cv::Mat Boundaries(const cv::Mat& labels) {
  cv::Mat edges(labels.size(), CV_8U, cv::Scalar(0));
  for (int y = 0; y < labels.rows; ++y) {
    const uint8_t* row = labels.ptr<uint8_t>(y);
    const uint8_t* below = y + 1 < labels.rows ? labels.ptr<uint8_t>(y + 1) : nullptr;
    uint8_t* out = edges.ptr<uint8_t>(y);
    for (int x = 0; x < labels.cols; ++x) {
      const bool right = x + 1 < labels.cols && row[x + 1] != row[x];
      const bool down = below != nullptr && below[x] != row[x];
      out[x] = (right || down) ? 255 : 0;
    }
  }
  return edges;
}

}  // namespace

cv::Scalar LabelColour(int label) {
  // The PASCAL VOC palette: bits of the label spread over the high bits of R, G and B.
  if (label == 0) return cv::Scalar(64, 64, 64);
  int r = 0;
  int g = 0;
  int b = 0;
  for (int i = 0, c = label; i < 8; ++i, c >>= 3) {
    r |= ((c >> 0) & 1) << (7 - i);
    g |= ((c >> 1) & 1) << (7 - i);
    b |= ((c >> 2) & 1) << (7 - i);
  }
  return cv::Scalar(b, g, r);
}

cv::Mat DrawLabelOverlay(const cv::Mat& image, const cv::Mat& labels, double alpha) {
  MOSLAM_CHECK(labels.type() == CV_8U && labels.size() == image.size());
  cv::Mat out = ToBgr(image);
  const cv::Mat edges = Boundaries(labels);
  for (int y = 0; y < out.rows; ++y) {
    cv::Vec3b* pixel = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < out.cols; ++x) {
      const cv::Scalar colour = LabelColour(labels.at<uint8_t>(y, x));
      const double a = edges.at<uint8_t>(y, x) != 0 ? 1.0 : alpha;
      for (int c = 0; c < 3; ++c) {
        pixel[x][c] = cv::saturate_cast<uint8_t>((1.0 - a) * pixel[x][c] + a * colour[c]);
      }
    }
  }
  return out;
}

cv::Mat DrawMaskOverlay(const cv::Mat& image, const cv::Mat& mask, const cv::Scalar& colour,
                        double alpha) {
  MOSLAM_CHECK(mask.type() == CV_8U && mask.size() == image.size());
  cv::Mat out = ToBgr(image);
  cv::Mat tinted = out.clone();
  tinted.setTo(colour, mask);
  cv::addWeighted(out, 1.0 - alpha, tinted, alpha, 0.0, out);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask != 0, contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
  cv::drawContours(out, contours, -1, colour, 1);
  return out;
}

cv::Mat SideBySide(const std::vector<cv::Mat>& panels, const std::vector<std::string>& titles) {
  MOSLAM_CHECK(!panels.empty() && titles.size() == panels.size());
  std::vector<cv::Mat> labelled;
  for (size_t i = 0; i < panels.size(); ++i) {
    MOSLAM_CHECK(panels[i].type() == CV_8UC3 && panels[i].rows == panels[0].rows);
    cv::Mat panel = panels[i].clone();
    const cv::Point at(6, 20);
    cv::putText(panel, titles[i], at, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 3);
    cv::putText(panel, titles[i], at, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(255, 255, 255), 1);
    labelled.push_back(panel);
  }
  cv::Mat out;
  cv::hconcat(labelled, out);
  return out;
}

}  // namespace moslam::semantic
