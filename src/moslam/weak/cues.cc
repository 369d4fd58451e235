#include "moslam/weak/cues.h"

#include <algorithm>
#include <array>
#include <vector>

#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc/slic.hpp>

#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/weak/image_list.h"

namespace moslam::weak {

namespace {

void RequireFraction(float value, const char* name, bool allow_zero) {
  const bool ok = allow_zero ? (value >= 0.0f && value <= 1.0f) : (value > 0.0f && value <= 1.0f);
  if (!ok) {
    ThrowInput("cues.{}: must be in {}0, 1], got {}", name, allow_zero ? "[" : "(", value);
  }
}

// The CAMs of the present classes (the background class excluded: its seeds come from the
// threshold rule of SEC, not from its own CAM), each ReLU'd and divided by its maximum over the
// image. A class whose maximum is not positive has no evidence anywhere and is left out.
std::vector<std::pair<int, cv::Mat>> NormalizedCams(const cv::Mat& cams,
                                                    const std::vector<int>& present,
                                                    int background) {
  const int num_classes = cams.size[0];
  std::vector<int> classes = present;
  std::sort(classes.begin(), classes.end());
  classes.erase(std::unique(classes.begin(), classes.end()), classes.end());
  std::vector<std::pair<int, cv::Mat>> normalized;
  for (int c : classes) {
    if (c < 0 || c >= num_classes) {
      ThrowInput("SeedsFromCams: present class {} out of range [0, {})", c, num_classes);
    }
    if (c == background) continue;
    const cv::Mat plane(cams.size[1], cams.size[2], CV_32F, const_cast<uchar*>(cams.ptr(c)));
    cv::Mat relu = cv::max(plane, 0.0f);
    double max_value = 0.0;
    cv::minMaxLoc(relu, nullptr, &max_value);
    if (!(max_value > 0.0)) continue;
    normalized.emplace_back(c, relu * (1.0 / max_value));
  }
  return normalized;
}

}  // namespace

void CueOptions::Check() const {
  RequireFraction(foreground_threshold, "foreground_threshold", /*allow_zero=*/false);
  RequireFraction(background_threshold, "background_threshold", /*allow_zero=*/false);
  if (background_threshold > foreground_threshold) {
    ThrowInput("cues.background_threshold ({}) must not exceed cues.foreground_threshold ({})",
               background_threshold, foreground_threshold);
  }
  if (superpixel_size < 2) {
    ThrowInput("cues.superpixel_size: must be >= 2 pixels, got {}", superpixel_size);
  }
  if (!(superpixel_ruler > 0.0f)) {
    ThrowInput("cues.superpixel_ruler: must be > 0, got {}", superpixel_ruler);
  }
  if (superpixel_iterations < 1) {
    ThrowInput("cues.superpixel_iterations: must be >= 1, got {}", superpixel_iterations);
  }
  // Agreement above one half makes the winning label unique.
  if (!(agreement > 0.5f && agreement <= 1.0f)) {
    ThrowInput("cues.agreement: must be in (0.5, 1], got {}", agreement);
  }
  RequireFraction(min_coverage, "min_coverage", /*allow_zero=*/false);
}

cv::Mat SeedsFromCams(const cv::Mat& cams, const std::vector<int>& present, int background,
                      const CueOptions& options) {
  options.Check();
  if (cams.dims != 3 || cams.type() != CV_32F) {
    ThrowInput("SeedsFromCams: cams must be a 3-D {{C, H, W}} CV_32F matrix (dims {}, type {})",
               cams.dims, cams.type());
  }
  if (!cams.isContinuous()) ThrowInput("SeedsFromCams: cams must be continuous");
  const int num_classes = cams.size[0];
  const int rows = cams.size[1];
  const int cols = cams.size[2];
  if (background < -1 || background >= num_classes) {
    ThrowInput("SeedsFromCams: background {} out of range [-1, {})", background, num_classes);
  }
  if (num_classes >= kUnknown) {
    ThrowInput("SeedsFromCams: {} classes do not fit an 8-bit cue map", num_classes);
  }
  const auto normalized = NormalizedCams(cams, present, background);

  cv::Mat seeds(rows, cols, CV_8UC1, cv::Scalar(kUnknown));
  for (int y = 0; y < rows; ++y) {
    unsigned char* out = seeds.ptr<unsigned char>(y);
    for (int x = 0; x < cols; ++x) {
      int best_class = -1;
      float best = -1.0f;
      // Classes are visited in increasing index: ties go to the lowest class.
      for (const auto& [c, cam] : normalized) {
        const float v = cam.at<float>(y, x);
        if (v > best) {
          best = v;
          best_class = c;
        }
      }
      if (best_class >= 0 && best >= options.foreground_threshold) {
        out[x] = static_cast<unsigned char>(best_class);
      } else if (background >= 0 && best < options.background_threshold) {
        // With no present foreground class (best = -1) the whole image is background.
        out[x] = static_cast<unsigned char>(background);
      }
    }
  }
  return seeds;
}

void SuppressAbsentInCells(cv::Mat& cams, const std::vector<std::vector<int>>& cell_classes,
                           int rows, int cols, bool per_cell_max) {
  if (cams.dims != 3 || cams.type() != CV_32F || !cams.isContinuous()) {
    ThrowInput("SuppressAbsentInCells: cams must be a continuous 3-D {{C, H, W}} CV_32F matrix");
  }
  if (rows < 1 || cols < 1 || cell_classes.size() != static_cast<size_t>(rows) * cols) {
    ThrowInput("SuppressAbsentInCells: {} cell label lists for a {}x{} grid", cell_classes.size(),
               cols, rows);
  }
  const int num_classes = cams.size[0];
  const int height = cams.size[1];
  const int width = cams.size[2];
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const std::vector<int>& present = cell_classes[static_cast<size_t>(r) * cols + c];
      const cv::Rect cell = GridCell(cv::Rect(0, 0, width, height), r, c, rows, cols);
      for (int k = 0; k < num_classes; ++k) {
        cv::Mat region = cv::Mat(height, width, CV_32F, cams.ptr(k))(cell);
        if (std::find(present.begin(), present.end(), k) == present.end()) {
          region.setTo(0.0f);
        } else if (per_cell_max) {
          cv::max(region, 0.0f, region);
          double max_value = 0.0;
          cv::minMaxLoc(region, nullptr, &max_value);
          if (max_value > 0.0) region *= 1.0 / max_value;
        }
      }
    }
  }
}

void ClearLabelInCells(cv::Mat& seeds, const std::vector<bool>& cells, int rows, int cols,
                       int label) {
  if (seeds.type() != CV_8UC1) ThrowInput("ClearLabelInCells: seeds must be CV_8UC1");
  if (rows < 1 || cols < 1 || cells.size() != static_cast<size_t>(rows) * cols) {
    ThrowInput("ClearLabelInCells: {} cell flags for a {}x{} grid", cells.size(), cols, rows);
  }
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      if (!cells[static_cast<size_t>(r) * cols + c]) continue;
      cv::Mat region = seeds(GridCell(cv::Rect(0, 0, seeds.cols, seeds.rows), r, c, rows, cols));
      region.setTo(kUnknown, region == label);
    }
  }
}

std::vector<int> MissedClasses(const cv::Mat& cue, const std::vector<int>& classes, int background,
                               float min_fraction) {
  if (cue.type() != CV_8UC1) ThrowInput("MissedClasses: cue must be CV_8UC1");
  std::vector<int> missed;
  for (int c : classes) {
    if (c == background) continue;
    if (cv::countNonZero(cue == c) < min_fraction * cue.total()) missed.push_back(c);
  }
  return missed;
}

void FillClassesFrom(const cv::Mat& source, const std::vector<int>& classes, cv::Mat& cue) {
  if (cue.type() != CV_8UC1 || source.type() != CV_8UC1) {
    ThrowInput("FillClassesFrom: cue and source must be CV_8UC1");
  }
  if (classes.empty() || cue.empty()) return;
  cv::Mat resized = source;
  if (source.size() != cue.size()) {
    cv::resize(source, resized, cue.size(), 0, 0, cv::INTER_NEAREST);
  }
  for (int c : classes) cue.setTo(c, resized == c);
}

cv::Mat RefineWithSuperpixels(const cv::Mat& seeds, const cv::Mat& image,
                              const CueOptions& options) {
  options.Check();
  if (seeds.type() != CV_8UC1) ThrowInput("RefineWithSuperpixels: seeds must be CV_8UC1");
  if (image.type() != CV_8UC3 && image.type() != CV_8UC1) {
    ThrowInput("RefineWithSuperpixels: image must be CV_8UC3 or CV_8UC1 (type {})", image.type());
  }
  if (image.size() != seeds.size()) {
    ThrowInput("RefineWithSuperpixels: image {}x{} and seeds {}x{} differ in size", image.cols,
               image.rows, seeds.cols, seeds.rows);
  }
  if (seeds.empty()) return seeds.clone();
  // Lab makes colour distances perceptual, which is what SLIC's distance assumes (Achanta et al.
  // 2012). Plain SLIC rather than SLICO: SLICO picks its compactness per superpixel and would
  // ignore superpixel_ruler, which is the option that trades colour adherence for regularity.
  // A light blur first, as in OpenCV's SLIC sample: pixel noise otherwise dominates the colour
  // term and fragments the superpixels.
  cv::Mat features;
  cv::GaussianBlur(image, features, cv::Size(3, 3), 0.0);
  if (image.channels() == 3) cv::cvtColor(features, features, cv::COLOR_BGR2Lab);
  auto slic = cv::ximgproc::createSuperpixelSLIC(features, cv::ximgproc::SLIC,
                                                 options.superpixel_size, options.superpixel_ruler);
  slic->iterate(options.superpixel_iterations);
  slic->enforceLabelConnectivity();
  cv::Mat labels;
  slic->getLabels(labels);
  const int num_superpixels = slic->getNumberOfSuperpixels();

  // Votes: per superpixel, its size and how many of its pixels carry each seed label.
  std::vector<int> size(num_superpixels, 0);
  std::vector<std::array<int, 256>> votes(num_superpixels);
  for (auto& v : votes) v.fill(0);
  for (int y = 0; y < seeds.rows; ++y) {
    const int* sp = labels.ptr<int>(y);
    const unsigned char* s = seeds.ptr<unsigned char>(y);
    for (int x = 0; x < seeds.cols; ++x) {
      MOSLAM_CHECK(sp[x] >= 0 && sp[x] < num_superpixels) << "superpixel " << sp[x];
      ++size[sp[x]];
      ++votes[sp[x]][s[x]];
    }
  }
  // The label each superpixel takes (kUnknown when its seeds are dropped).
  std::vector<unsigned char> decision(num_superpixels, kUnknown);
  for (int i = 0; i < num_superpixels; ++i) {
    const int seeded = size[i] - votes[i][kUnknown];
    if (seeded == 0 || seeded < options.min_coverage * size[i]) continue;
    for (int l = 0; l < kUnknown; ++l) {
      if (votes[i][l] >= options.agreement * seeded) {
        decision[i] = static_cast<unsigned char>(l);
        break;
      }
    }
  }
  cv::Mat refined(seeds.size(), CV_8UC1);
  for (int y = 0; y < seeds.rows; ++y) {
    const int* sp = labels.ptr<int>(y);
    unsigned char* out = refined.ptr<unsigned char>(y);
    for (int x = 0; x < seeds.cols; ++x) out[x] = decision[sp[x]];
  }
  return refined;
}

cv::Mat FuseCues(const cv::Mat& colour, const cv::Mat& grey, bool one_sided) {
  if (colour.type() != CV_8UC1 || grey.type() != CV_8UC1 || colour.size() != grey.size()) {
    ThrowInput("FuseCues: cues must be CV_8UC1 of one size ({}x{} type {} vs {}x{} type {})",
               colour.cols, colour.rows, colour.type(), grey.cols, grey.rows, grey.type());
  }
  cv::Mat fused(colour.size(), CV_8UC1);
  for (int y = 0; y < colour.rows; ++y) {
    const unsigned char* a = colour.ptr<unsigned char>(y);
    const unsigned char* b = grey.ptr<unsigned char>(y);
    unsigned char* out = fused.ptr<unsigned char>(y);
    for (int x = 0; x < colour.cols; ++x) {
      if (a[x] == b[x]) {
        out[x] = a[x];
      } else if (a[x] == kUnknown || b[x] == kUnknown) {
        out[x] = one_sided ? (a[x] == kUnknown ? b[x] : a[x]) : kUnknown;
      } else {
        out[x] = kUnknown;  // the two classifiers disagree
      }
    }
  }
  return fused;
}

cv::Mat CuesFromSegmentation(const cv::Mat& probabilities, const std::vector<int>& present,
                             int background, const cv::Mat& image, const cv::Mat& depth_m,
                             semantic::DenseCrf& crf, float confidence) {
  if (probabilities.dims != 3 || probabilities.type() != CV_32F || !probabilities.isContinuous()) {
    ThrowInput(
        "CuesFromSegmentation: probabilities must be a continuous {{C, H, W}} CV_32F matrix");
  }
  const int num_classes = probabilities.size[0];
  if (num_classes < 2 || num_classes >= kUnknown) {
    ThrowInput("CuesFromSegmentation: {} classes (2 to {} supported)", num_classes, kUnknown - 1);
  }
  if (image.rows != probabilities.size[1] || image.cols != probabilities.size[2]) {
    ThrowInput("CuesFromSegmentation: image {}x{} and probabilities {}x{} differ in size",
               image.cols, image.rows, probabilities.size[2], probabilities.size[1]);
  }
  if (!(confidence > 0.0f && confidence <= 1.0f)) {
    ThrowInput("CuesFromSegmentation: confidence must be in (0, 1], got {}", confidence);
  }
  std::vector<bool> keep(num_classes, false);
  if (background >= 0 && background < num_classes) keep[background] = true;
  for (int c : present) {
    if (c < 0 || c >= num_classes) {
      ThrowInput("CuesFromSegmentation: present class {} out of range [0, {})", c, num_classes);
    }
    keep[c] = true;
  }
  // Absent classes get probability zero (the CRF clamps it to its minimum, a large energy), so
  // neither the CRF nor the cue can choose them.
  cv::Mat unaries = probabilities.clone();
  for (int c = 0; c < num_classes; ++c) {
    if (!keep[c]) semantic::LabelPlane(unaries, c).setTo(0.0f);
  }
  const semantic::CrfResult result =
      crf.Infer(image, depth_m, semantic::Unaries::FromProbabilities(unaries));
  cv::Mat cues(image.size(), CV_8UC1, cv::Scalar(kUnknown));
  for (int y = 0; y < image.rows; ++y) {
    const unsigned char* label = result.labels.ptr<unsigned char>(y);
    unsigned char* out = cues.ptr<unsigned char>(y);
    for (int x = 0; x < image.cols; ++x) {
      const int l = label[x];
      if (keep[l] && result.marginals.at<float>(l, y, x) >= confidence) {
        out[x] = static_cast<unsigned char>(l);
      }
    }
  }
  return cues;
}

namespace {

cv::Mat AsBgr(const cv::Mat& image, const char* function) {
  if (image.type() == CV_8UC3) return image;
  if (image.type() == CV_8UC1) {
    cv::Mat bgr;
    cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
    return bgr;
  }
  ThrowInput("{}: image must be CV_8UC3 or CV_8UC1 (type {})", function, image.type());
}

// Distinct BGR colours (the CamVid palette's first entries, then saturated hues); class indices
// beyond the palette wrap around.
constexpr std::array<std::array<unsigned char, 3>, 16> kPalette = {{
    {128, 128, 128},
    {0, 0, 128},
    {128, 64, 128},
    {222, 40, 60},
    {0, 128, 128},
    {128, 128, 192},
    {128, 64, 64},
    {128, 0, 64},
    {0, 64, 64},
    {0, 128, 192},
    {192, 128, 64},
    {0, 255, 0},
    {255, 0, 255},
    {0, 255, 255},
    {255, 255, 0},
    {255, 128, 0},
}};

}  // namespace

cv::Mat RenderCue(const cv::Mat& cue, const cv::Mat& image) {
  const cv::Mat bgr = AsBgr(image, "RenderCue");
  if (cue.type() != CV_8UC1 || cue.size() != image.size()) {
    ThrowInput("RenderCue: cue must be CV_8UC1 of the image's size");
  }
  cv::Mat colours(cue.size(), CV_8UC3);
  for (int y = 0; y < cue.rows; ++y) {
    const unsigned char* c = cue.ptr<unsigned char>(y);
    cv::Vec3b* out = colours.ptr<cv::Vec3b>(y);
    for (int x = 0; x < cue.cols; ++x) {
      if (c[x] == kUnknown) {
        out[x] = cv::Vec3b(0, 0, 0);
      } else {
        const auto& p = kPalette[c[x] % kPalette.size()];
        out[x] = cv::Vec3b(p[0], p[1], p[2]);
      }
    }
  }
  cv::Mat blended;
  cv::addWeighted(bgr, 0.4, colours, 0.6, 0.0, blended);
  return blended;
}

cv::Mat RenderCam(const cv::Mat& cam, const cv::Mat& image) {
  const cv::Mat bgr = AsBgr(image, "RenderCam");
  if (cam.type() != CV_32FC1 || cam.empty()) ThrowInput("RenderCam: cam must be 2-D CV_32FC1");
  cv::Mat relu = cv::max(cam, 0.0f);
  if (relu.size() != image.size()) {
    cv::resize(relu, relu, image.size(), 0, 0, cv::INTER_LINEAR);
  }
  double max_value = 0.0;
  cv::minMaxLoc(relu, nullptr, &max_value);
  cv::Mat scaled;
  relu.convertTo(scaled, CV_8U, max_value > 0.0 ? 255.0 / max_value : 0.0);
  cv::Mat heat;
  cv::applyColorMap(scaled, heat, cv::COLORMAP_JET);
  cv::Mat blended;
  cv::addWeighted(bgr, 0.5, heat, 0.5, 0.0, blended);
  return blended;
}

}  // namespace moslam::weak
