#include "moslam/weak/evaluation.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "moslam/util/error.h"
#include "moslam/util/strings.h"

namespace moslam::weak {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Label id -> class index; kIgnored for ignored ids, -1 for ids without a counterpart.
constexpr int kIgnored = -2;

double Ratio(double numerator, double denominator) {
  return denominator > 0.0 ? numerator / denominator : kNaN;
}

nlohmann::json Number(double value) {
  // JSON has no NaN; null says "undefined" (a class absent from both truth and prediction).
  return std::isnan(value) ? nlohmann::json(nullptr) : nlohmann::json(value);
}

}  // namespace

SegEvaluator::SegEvaluator(std::vector<std::string> class_names, SegEvalOptions options)
    : class_names_(std::move(class_names)), options_(std::move(options)) {
  const int classes = static_cast<int>(class_names_.size());
  if (classes < 1 || classes > 255) {
    ThrowInput("segmentation evaluation: 1 to 255 classes expected, got {}", classes);
  }
  if (!options_.movable_classes.empty() &&
      static_cast<int>(options_.movable_classes.size()) != classes) {
    ThrowInput("segmentation evaluation: movable_classes has {} flags for {} classes",
               options_.movable_classes.size(), classes);
  }
  for (int c : options_.label_to_class) {
    if (c < -1 || c >= classes) {
      ThrowInput("segmentation evaluation: label_to_class maps to {}, not a class (0..{}) or -1", c,
                 classes - 1);
    }
  }
  if (options_.label_to_class.size() > 256 || options_.movable_labels.size() > 256) {
    ThrowInput("segmentation evaluation: label ids are 8-bit (at most 256 entries)");
  }
  // Lookup tables over the 256 possible label ids.
  class_of_label_.assign(256, -1);
  truth_movable_.assign(256, false);
  for (int id = 0; id < 256; ++id) {
    if (options_.label_to_class.empty()) {
      class_of_label_[id] = id < classes ? id : -1;
    } else if (id < static_cast<int>(options_.label_to_class.size())) {
      class_of_label_[id] = options_.label_to_class[id];
    }
    if (options_.movable_labels.empty()) {
      // Without explicit flags a label is movable when its class is.
      const int c = class_of_label_[id];
      truth_movable_[id] = c >= 0 && IsMovableClass(c);
    } else {
      truth_movable_[id] =
          id < static_cast<int>(options_.movable_labels.size()) && options_.movable_labels[id];
    }
  }
  for (int id : options_.ignore_labels) {
    if (id < 0 || id > 255) ThrowInput("segmentation evaluation: ignore label {} is not 8-bit", id);
    class_of_label_[id] = kIgnored;
  }
  confusion_ = cv::Mat::zeros(classes, classes, CV_64F);
  unmatched_ = cv::Mat::zeros(1, classes, CV_64F);
}

bool SegEvaluator::IsMovableClass(int c) const {
  return !options_.movable_classes.empty() && options_.movable_classes[c];
}

double SegEvaluator::Add(const cv::Mat& prediction, const cv::Mat& labels) {
  if (prediction.type() != CV_8UC1 || labels.type() != CV_8UC1) {
    ThrowInput("segmentation evaluation: prediction and labels must be 8-bit single-channel");
  }
  if (prediction.size() != labels.size()) {
    ThrowInput("segmentation evaluation: prediction is {}x{}, labels are {}x{}", prediction.cols,
               prediction.rows, labels.cols, labels.rows);
  }
  const int classes = num_classes();
  // Counted per image first (integers, exact), then added to the running totals.
  cv::Mat confusion = cv::Mat::zeros(classes, classes, CV_64F);
  cv::Mat unmatched = cv::Mat::zeros(1, classes, CV_64F);
  double tp = 0, fp = 0, fn = 0, ignored = 0;
  for (int y = 0; y < labels.rows; ++y) {
    const uint8_t* p = prediction.ptr<uint8_t>(y);
    const uint8_t* l = labels.ptr<uint8_t>(y);
    for (int x = 0; x < labels.cols; ++x) {
      const int truth = class_of_label_[l[x]];
      if (truth == kIgnored) {
        ++ignored;
        continue;
      }
      const int predicted = p[x];
      if (predicted >= classes) {
        ThrowInput("segmentation evaluation: predicted class {} at ({}, {}) but there are {}",
                   predicted, x, y, classes);
      }
      if (truth >= 0) {
        ++confusion.at<double>(truth, predicted);
      } else {
        ++unmatched.at<double>(0, predicted);
      }
      const bool t = truth_movable_[l[x]];
      const bool m = IsMovableClass(predicted);
      tp += t && m;
      fp += !t && m;
      fn += t && !m;
    }
  }
  confusion_ += confusion;
  unmatched_ += unmatched;
  movable_tp_ += tp;
  movable_fp_ += fp;
  movable_fn_ += fn;
  ignored_pixels_ += ignored;
  ++images_;
  const double union_ = tp + fp + fn;
  return union_ > 0.0 ? tp / union_ : 1.0;
}

std::vector<double> SegEvaluator::ClassIoU() const {
  const int classes = num_classes();
  std::vector<double> iou(classes);
  for (int c = 0; c < classes; ++c) {
    const double tp = confusion_.at<double>(c, c);
    const double truth = cv::sum(confusion_.row(c))[0];
    // A pixel whose label has no class is a false positive of whatever was predicted there.
    const double predicted = cv::sum(confusion_.col(c))[0] + unmatched_.at<double>(0, c);
    iou[c] = Ratio(tp, truth + predicted - tp);
  }
  return iou;
}

double SegEvaluator::MeanIoU() const {
  double sum = 0.0;
  int count = 0;
  for (double v : ClassIoU()) {
    if (std::isnan(v)) continue;
    sum += v;
    ++count;
  }
  return count > 0 ? sum / count : kNaN;
}

double SegEvaluator::MovableIoU() const {
  const double union_ = movable_tp_ + movable_fp_ + movable_fn_;
  return union_ > 0.0 ? movable_tp_ / union_ : 1.0;
}

double SegEvaluator::MovablePrecision() const {
  return Ratio(movable_tp_, movable_tp_ + movable_fp_);
}

double SegEvaluator::MovableRecall() const { return Ratio(movable_tp_, movable_tp_ + movable_fn_); }

double SegEvaluator::PixelAccuracy() const {
  const double counted = cv::sum(confusion_)[0] + cv::sum(unmatched_)[0];
  return Ratio(cv::trace(confusion_)[0], counted);
}

nlohmann::json SegEvaluator::ToJson() const {
  const std::vector<double> iou = ClassIoU();
  nlohmann::json classes = nlohmann::json::array();
  for (int c = 0; c < num_classes(); ++c) {
    classes.push_back(
        {{"name", class_names_[c]},
         {"iou", Number(iou[c])},
         {"movable", IsMovableClass(c)},
         {"truth_pixels", cv::sum(confusion_.row(c))[0]},
         {"predicted_pixels", cv::sum(confusion_.col(c))[0] + unmatched_.at<double>(0, c)}});
  }
  nlohmann::json confusion = nlohmann::json::array();
  for (int r = 0; r < confusion_.rows; ++r) {
    std::vector<double> row(confusion_.ptr<double>(r), confusion_.ptr<double>(r) + confusion_.cols);
    confusion.push_back(row);
  }
  const std::vector<double> unmatched(unmatched_.ptr<double>(0),
                                      unmatched_.ptr<double>(0) + unmatched_.cols);
  return {{"images", images_},
          {"classes", classes},
          {"mean_iou", Number(MeanIoU())},
          {"pixel_accuracy", Number(PixelAccuracy())},
          {"movable",
           {{"iou", Number(MovableIoU())},
            {"precision", Number(MovablePrecision())},
            {"recall", Number(MovableRecall())},
            {"true_positives", movable_tp_},
            {"false_positives", movable_fp_},
            {"false_negatives", movable_fn_}}},
          {"ignored_labels", options_.ignore_labels},
          {"ignored_pixels", ignored_pixels_},
          {"confusion", confusion},
          {"unmatched_label_pixels", unmatched}};
}

const std::vector<std::string>& CamVidLabelNames() {
  static const std::vector<std::string> names = {"Sky",      "Building",   "Pole",       "Road",
                                                 "Pavement", "Tree",       "SignSymbol", "Fence",
                                                 "Car",      "Pedestrian", "Bicyclist"};
  return names;
}

std::vector<int> LabelToClassByName(const std::vector<std::string>& label_names,
                                    const std::vector<std::string>& classes, int background) {
  std::vector<int> mapping(label_names.size(), background);
  bool matched = false;
  for (size_t id = 0; id < label_names.size(); ++id) {
    for (size_t c = 0; c < classes.size(); ++c) {
      if (ToLower(classes[c]) != ToLower(label_names[id])) continue;
      mapping[id] = static_cast<int>(c);
      matched = true;
    }
  }
  return matched ? mapping : std::vector<int>();
}

cv::Mat RenderConfusion(const cv::Mat& confusion, const std::vector<std::string>& class_names) {
  const int n = confusion.rows;
  if (confusion.type() != CV_64F || confusion.cols != n ||
      static_cast<int>(class_names.size()) != n || n == 0) {
    ThrowInput("confusion image: expected a square CV_64F matrix with one name per class");
  }
  constexpr int kCell = 44;
  constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
  constexpr double kScale = 0.45;
  int name_width = 0;
  for (const std::string& name : class_names) {
    int baseline = 0;
    name_width = std::max(name_width, cv::getTextSize(name, kFont, kScale, 1, &baseline).width);
  }
  const int margin = name_width + 12;
  const int caption = 22;
  cv::Mat image(margin + n * kCell + caption, margin + n * kCell + 4, CV_8UC3,
                cv::Scalar(255, 255, 255));
  // Cells: the share of each true class (row) predicted as each class (column), on a white to
  // blue scale; a class without ground-truth pixels has a grey row.
  for (int r = 0; r < n; ++r) {
    const double total = cv::sum(confusion.row(r))[0];
    for (int c = 0; c < n; ++c) {
      const cv::Rect cell(margin + c * kCell, margin + r * kCell, kCell, kCell);
      if (total <= 0.0) {
        cv::rectangle(image, cell, cv::Scalar(215, 215, 215), cv::FILLED);
        continue;
      }
      const double share = confusion.at<double>(r, c) / total;
      const double fade = 1.0 - share;
      cv::rectangle(image, cell, cv::Scalar(255, 80 + 175 * fade, 30 + 225 * fade), cv::FILLED);
      const std::string text = fmt::format("{:.0f}", 100.0 * share);
      const cv::Scalar ink = share > 0.5 ? cv::Scalar(255, 255, 255) : cv::Scalar(40, 40, 40);
      cv::putText(image, text, cell.tl() + cv::Point(8, kCell / 2 + 5), kFont, kScale, ink, 1,
                  cv::LINE_AA);
    }
  }
  for (int i = 0; i <= n; ++i) {
    const int at = margin + i * kCell;
    cv::line(image, {margin, at}, {margin + n * kCell, at}, cv::Scalar(160, 160, 160));
    cv::line(image, {at, margin}, {at, margin + n * kCell}, cv::Scalar(160, 160, 160));
  }
  // Row names (truth) at the left; column names (prediction) written vertically above.
  cv::Mat top(name_width + 12, n * kCell, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::Mat top_rotated;
  cv::rotate(top, top_rotated, cv::ROTATE_90_CLOCKWISE);  // n*kCell x (name_width + 12)
  for (int i = 0; i < n; ++i) {
    cv::putText(image, class_names[i], {4, margin + i * kCell + kCell / 2 + 5}, kFont, kScale,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::putText(top_rotated, class_names[i], {4, i * kCell + kCell / 2 + 5}, kFont, kScale,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  cv::rotate(top_rotated, top, cv::ROTATE_90_COUNTERCLOCKWISE);
  top.copyTo(image(cv::Rect(margin, 0, top.cols, top.rows)));
  cv::putText(image, "rows: truth, columns: predicted, % of the row", {4, image.rows - 7}, kFont,
              kScale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return image;
}

}  // namespace moslam::weak
