#include "moslam/weak/augment.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::weak {
namespace {

// Uniform in [0, 1) from the top 53 bits. Hand-written rather than std::uniform_real_distribution
// because the standard leaves that distribution's algorithm to the library: this keeps a seed's
// augmentations identical across standard libraries, not only across runs.
double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

double Uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * Uniform01(rng);
}

// Uniform integer in [lo, hi] (both included).
int UniformInt(std::mt19937_64& rng, int lo, int hi) {
  const auto span = static_cast<uint64_t>(hi - lo) + 1;
  return lo + static_cast<int>(Uniform01(rng) * static_cast<double>(span));
}

void CheckRange(double value, double lo, double hi, bool lo_open, const char* field) {
  const bool ok = (lo_open ? value > lo : value >= lo) && value <= hi;
  if (!ok) {
    ThrowInput("AugmentOptions.{}: must be in {}{}, {}], got {}", field, lo_open ? "(" : "[", lo,
               hi, value);
  }
}

// The crop of an image of `size`: with probability crop_probability a window whose sides are the
// same fraction s ~ U[min_scale, max_scale] of the image's (aspect ratio kept), placed uniformly.
cv::Rect DrawCrop(const cv::Size& size, const AugmentOptions& options, std::mt19937_64& rng) {
  const cv::Rect whole(0, 0, size.width, size.height);
  if (Uniform01(rng) >= options.crop_probability) return whole;
  const double s = Uniform(rng, options.min_scale, options.max_scale);
  const int w = std::clamp(static_cast<int>(std::lround(s * size.width)), 1, size.width);
  const int h = std::clamp(static_cast<int>(std::lround(s * size.height)), 1, size.height);
  const int x = UniformInt(rng, 0, size.width - w);
  const int y = UniformInt(rng, 0, size.height - h);
  return cv::Rect(x, y, w, h);
}

cv::Mat ResizeImage(const cv::Mat& image, const cv::Size& size) {
  if (image.size() == size) return image.clone();
  // INTER_AREA when shrinking avoids aliasing; it degenerates to nearest neighbour when
  // enlarging, where INTER_LINEAR is the better choice.
  const bool shrinking = size.area() < image.size().area();
  cv::Mat out;
  cv::resize(image, out, size, 0, 0, shrinking ? cv::INTER_AREA : cv::INTER_LINEAR);
  return out;
}

// Saturation, contrast, brightness jitter (the order and factor ranges of torchvision's
// ColorJitter, each factor 1 + U[-x, x]).
void JitterColour(cv::Mat& bgr, const AugmentOptions& options, std::mt19937_64& rng) {
  const double saturation = 1.0 + Uniform(rng, -options.saturation, options.saturation);
  const double contrast = 1.0 + Uniform(rng, -options.contrast, options.contrast);
  const double brightness = 1.0 + Uniform(rng, -options.brightness, options.brightness);
  cv::Mat f;
  bgr.convertTo(f, CV_32FC3);
  cv::Mat grey;
  cv::cvtColor(f, grey, cv::COLOR_BGR2GRAY);
  if (!options.grey) {
    cv::Mat grey3;
    cv::cvtColor(grey, grey3, cv::COLOR_GRAY2BGR);
    cv::addWeighted(f, saturation, grey3, 1.0 - saturation, 0.0, f);
  }
  const double mean = cv::mean(grey)[0];
  f.convertTo(f, CV_32FC3, contrast, (1.0 - contrast) * mean);
  f.convertTo(bgr, CV_8UC3, brightness);  // saturates to [0, 255]
}

cv::Mat ReadColour(const std::string& path) {
  cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  if (image.empty()) ThrowInFile(path, "cannot be read as an image");
  return image;
}

cv::Mat ReadSingleChannel(const std::string& path, const cv::Size& size, const char* what) {
  cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (m.empty()) ThrowInFile(path, fmt::format("cannot be read as {}", what));
  if (m.type() != CV_8UC1) ThrowInFile(path, fmt::format("{} must be 8-bit single-channel", what));
  if (m.size() != size) {
    ThrowInFile(path, fmt::format("{} is {}x{}, its image {}x{}", what, m.cols, m.rows, size.width,
                                  size.height));
  }
  return m;
}

// Classes in `roi` of the label image `ids`, mapped to the list's classes (label_to_class).
std::vector<int> RoiClasses(const ImageList& list, const cv::Mat& ids, const cv::Rect& roi) {
  if (list.label_to_class.empty()) {
    return CropLabels(ids, roi, list.num_classes(), list.label_min_fraction);
  }
  std::vector<int> classes;
  for (int id : CropLabels(ids, roi, static_cast<int>(list.label_to_class.size()),
                           list.label_min_fraction)) {
    if (list.label_to_class[id] >= 0) classes.push_back(list.label_to_class[id]);
  }
  std::sort(classes.begin(), classes.end());
  classes.erase(std::unique(classes.begin(), classes.end()), classes.end());
  return classes;
}

// Labels of the sample: entries with a label image are relabelled by what the crop contains;
// others keep the whole image's labels. The latter is an approximation: a crop may cut away every
// pixel of a labelled class (the loss then sees a false positive label); min_scale bounds how much
// is cut. With a label grid (and a label image), also the labels of each cell of the crop, in the
// sample's frame: a flipped sample's column c is the crop's column cols - 1 - c.
void LabelSample(const ImageList& list, const ImageListEntry& entry, const cv::Rect& roi,
                 const cv::Size& size, const AugmentOptions& options, bool flip, Sample* sample) {
  const bool whole = roi == cv::Rect(0, 0, size.width, size.height);
  const bool grid = options.label_grid_cols > 0 && !entry.label_image.empty();
  if (entry.label_image.empty() || (whole && !grid)) {
    sample->classes = entry.classes;
    return;
  }
  const cv::Mat ids = ReadSingleChannel(entry.label_image, size, "a label image");
  sample->classes = whole ? entry.classes : RoiClasses(list, ids, roi);
  if (!grid) return;
  const int cols = options.label_grid_cols;
  const int rows = options.label_grid_rows;
  MOSLAM_CHECK(roi.width >= cols && roi.height >= rows)
      << "a " << roi.width << "x" << roi.height << " crop cannot hold a " << cols << "x" << rows
      << " label grid";
  sample->cell_classes.assign(static_cast<size_t>(rows) * cols, {});
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int out_c = flip ? cols - 1 - c : c;
      sample->cell_classes[static_cast<size_t>(r) * cols + out_c] =
          RoiClasses(list, ids, GridCell(roi, r, c, rows, cols));
    }
  }
}

}  // namespace

void AugmentOptions::Check() const {
  if (output_width < 1 || output_height < 1) {
    ThrowInput("AugmentOptions.output_width/output_height: must be >= 1 pixel, got {}x{}",
               output_width, output_height);
  }
  CheckRange(min_scale, 0.0, 1.0, true, "min_scale");
  CheckRange(max_scale, 0.0, 1.0, true, "max_scale");
  if (min_scale > max_scale) {
    ThrowInput("AugmentOptions.min_scale: must be <= max_scale ({}), got {}", max_scale, min_scale);
  }
  CheckRange(crop_probability, 0.0, 1.0, false, "crop_probability");
  // A factor 1 - x must stay positive.
  CheckRange(brightness, 0.0, 0.99, false, "brightness");
  CheckRange(contrast, 0.0, 0.99, false, "contrast");
  CheckRange(saturation, 0.0, 0.99, false, "saturation");
  if (label_grid_cols < 0 || label_grid_rows < 0 ||
      (label_grid_cols == 0) != (label_grid_rows == 0)) {
    ThrowInput(
        "AugmentOptions.label_grid_cols/label_grid_rows: both 0 (no grid) or both >= 1, got "
        "{}x{}",
        label_grid_cols, label_grid_rows);
  }
}

Sample LoadSample(const ImageList& list, int index, const AugmentOptions& options,
                  std::mt19937_64& rng, bool augment, const std::string& cue_path) {
  options.Check();
  MOSLAM_CHECK(index >= 0 && index < static_cast<int>(list.entries.size()))
      << "entry " << index << " of " << list.entries.size();
  const ImageListEntry& entry = list.entries[index];
  const cv::Mat image = ReadColour(entry.image);
  cv::Mat cue;
  if (!cue_path.empty()) cue = ReadSingleChannel(cue_path, image.size(), "a cue map");

  // Random draws in a fixed order (crop, flip, colour) so that a seed fixes the sample.
  const cv::Rect roi =
      augment ? DrawCrop(image.size(), options, rng) : cv::Rect(0, 0, image.cols, image.rows);
  const bool flip = augment && options.flip && Uniform01(rng) < 0.5;

  const cv::Size out_size(options.output_width, options.output_height);
  Sample sample;
  sample.index = index;
  LabelSample(list, entry, roi, image.size(), options, flip, &sample);
  sample.image = ResizeImage(image(roi), out_size);
  if (!cue.empty()) {
    // INTER_NEAREST_EXACT rather than INTER_NEAREST: the latter samples floor(x * scale), half a
    // source pixel off the centres that the image's interpolation uses; the exact variant keeps
    // cue and image aligned (both are nearest neighbour, no label is ever blended).
    cv::resize(cue(roi), sample.cue, out_size, 0, 0, cv::INTER_NEAREST_EXACT);
  }
  if (flip) {
    cv::flip(sample.image, sample.image, 1);
    if (!sample.cue.empty()) cv::flip(sample.cue, sample.cue, 1);
  }
  if (augment) JitterColour(sample.image, options, rng);
  if (options.grey) {
    // Grey is the network's input type, not an augmentation: applied with augment false too.
    cv::Mat grey;
    cv::cvtColor(sample.image, grey, cv::COLOR_BGR2GRAY);
    cv::cvtColor(grey, sample.image, cv::COLOR_GRAY2BGR);
  }
  return sample;
}

void RequireLabelImages(const ImageList& list, const AugmentOptions& options,
                        const std::string& what) {
  if (options.label_grid_cols == 0) return;
  for (const ImageListEntry& entry : list.entries) {
    if (entry.label_image.empty()) {
      ThrowInput(
          "{}: a label grid needs crop labels, which only data with label images has (CamVid, "
          "or synthetic frames with --synthetic-crop-labels); {} has none",
          what, entry.image);
    }
  }
}

torch::Tensor ToInputTensor(const cv::Mat& image) {
  MOSLAM_CHECK(image.type() == CV_8UC3 || image.type() == CV_8UC1)
      << "ToInputTensor: 8-bit BGR or grey image expected";
  cv::Mat rgb;
  cv::cvtColor(image, rgb, image.channels() == 1 ? cv::COLOR_GRAY2RGB : cv::COLOR_BGR2RGB);
  cv::Mat f;
  rgb.convertTo(f, CV_32FC3, 1.0 / 127.5, -1.0);
  // from_blob borrows f's buffer; clone() after the permute owns contiguous 3 x H x W memory.
  return torch::from_blob(f.data, {f.rows, f.cols, 3}, torch::kFloat32)
      .permute({2, 0, 1})
      .contiguous()
      .clone();
}

Batch MakeBatch(const std::vector<Sample>& samples, int num_classes, int grid_rows, int grid_cols) {
  MOSLAM_CHECK(!samples.empty()) << "MakeBatch: no samples";
  MOSLAM_CHECK(num_classes > 0);
  MOSLAM_CHECK(grid_rows >= 0 && grid_cols >= 0 && (grid_rows == 0) == (grid_cols == 0));
  const size_t cells = static_cast<size_t>(grid_rows) * grid_cols;
  const cv::Size size = samples.front().image.size();
  const bool with_cues = !samples.front().cue.empty();
  const auto n = static_cast<int64_t>(samples.size());
  Batch batch;
  std::vector<torch::Tensor> images;
  batch.labels = torch::zeros({n, num_classes}, torch::kFloat32);
  auto labels = batch.labels.accessor<float, 2>();
  if (with_cues) batch.cues = torch::empty({n, size.height, size.width}, torch::kInt64);
  if (cells > 0) batch.cell_labels = torch::zeros({n, num_classes, grid_rows, grid_cols});
  for (int64_t i = 0; i < n; ++i) {
    const Sample& s = samples[i];
    MOSLAM_CHECK(s.image.size() == size) << "MakeBatch: samples differ in size";
    MOSLAM_CHECK(s.cue.empty() != with_cues) << "MakeBatch: some samples have cues, some not";
    images.push_back(ToInputTensor(s.image));
    for (const int c : s.classes) {
      MOSLAM_CHECK(c >= 0 && c < num_classes) << "class " << c << " of " << num_classes;
      labels[i][c] = 1.0f;
    }
    if (cells > 0) {
      MOSLAM_CHECK(s.cell_classes.size() == cells)
          << "MakeBatch: sample " << i << " has " << s.cell_classes.size() << " cell labels, the "
          << grid_rows << "x" << grid_cols << " grid " << cells;
      auto cell = batch.cell_labels.accessor<float, 4>();
      for (size_t k = 0; k < cells; ++k) {
        for (const int c : s.cell_classes[k]) {
          MOSLAM_CHECK(c >= 0 && c < num_classes) << "class " << c << " of " << num_classes;
          cell[i][c][k / grid_cols][k % grid_cols] = 1.0f;
        }
      }
    }
    if (with_cues) {
      MOSLAM_CHECK(s.cue.type() == CV_8UC1 && s.cue.size() == size) << "cue of sample " << i;
      const cv::Mat cue = s.cue.isContinuous() ? s.cue : s.cue.clone();
      batch.cues[i].copy_(
          torch::from_blob(cue.data, {size.height, size.width}, torch::kUInt8).to(torch::kInt64));
    }
    batch.bgr.push_back(s.image);
    batch.indices.push_back(s.index);
  }
  batch.images = torch::stack(images);
  return batch;
}

}  // namespace moslam::weak
