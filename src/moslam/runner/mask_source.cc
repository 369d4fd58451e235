#include "moslam/runner/mask_source.h"

#include <algorithm>
#include <filesystem>
#include <set>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/io/class_list.h"
#include "moslam/runner/model_mask_source.h"
#include "moslam/semantic/input_limits.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam::runner {
namespace fs = std::filesystem;

const char* ToString(MaskSourceKind kind) {
  switch (kind) {
    case MaskSourceKind::kNone:
      return "none";
    case MaskSourceKind::kFiles:
      return "files";
    case MaskSourceKind::kSynthGt:
      return "synth-gt";
    case MaskSourceKind::kOnnx:
      return "onnx";
    case MaskSourceKind::kDetector:
      return "detector";
    case MaskSourceKind::kModel:
      return "model";
  }
  return "?";
}

std::optional<MaskSourceKind> ParseMaskSourceKind(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "none") return MaskSourceKind::kNone;
  if (lower == "files") return MaskSourceKind::kFiles;
  if (lower == "synth-gt") return MaskSourceKind::kSynthGt;
  if (lower == "onnx") return MaskSourceKind::kOnnx;
  if (lower == "detector") return MaskSourceKind::kDetector;
  if (lower == "model") return MaskSourceKind::kModel;
  return std::nullopt;
}

bool IsModelSource(MaskSourceKind kind) {
  return kind == MaskSourceKind::kOnnx || kind == MaskSourceKind::kDetector ||
         kind == MaskSourceKind::kModel;
}

void MaskOptions::Check() const {
  if (kind == MaskSourceKind::kFiles && folder.empty()) {
    ThrowInput("--mask-source files: give the folder of mask PNGs (--mask-source files DIR)");
  }
  const bool model = IsModelSource(kind);
  if (network_threads < 0) ThrowInput("network threads: must be >= 0, got {}", network_threads);
  if (kind != MaskSourceKind::kSynthGt && !model && !movable.empty()) {
    ThrowInput("--movable: applies to --mask-source synth-gt, onnx, detector and model only");
  }
  if (model && kind != MaskSourceKind::kModel && model_card.empty()) {
    ThrowInput("--mask-source {}: give the model card (--model-card configs/models/<name>.yaml)",
               ToString(kind));
  }
  if (!model && !model_card.empty()) {
    ThrowInput("--model-card: applies to --mask-source onnx, detector and model only");
  }
  if (!model && crf && *crf != semantic::CrfMode::kNone) {
    ThrowInput("--crf: applies to --mask-source onnx, detector and model only");
  }
  if (dilate_px < 0 || dilate_px > semantic::kMaxDilatePx) {
    ThrowInput("--mask-dilate: must be in [0, {}] pixels, got {}", semantic::kMaxDilatePx,
               dilate_px);
  }
}

std::string MaskPathFor(const std::string& folder, const io::FrameEntry& frame) {
  return (fs::path(folder) / fs::path(frame.image_left).stem()).string() + ".png";
}

namespace {

// Reads a single-channel 8-bit image of `size` (the mask or class image of a frame).
cv::Mat ReadLabelImage(const std::string& path, const cv::Size& size, const char* what) {
  const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) ThrowInFile(path, fmt::format("cannot be read as {}", what));
  if (image.type() != CV_8UC1) {
    ThrowInFile(path, fmt::format("{} must be an 8-bit single-channel image", what));
  }
  if (image.size() != size) {
    ThrowInFile(path, fmt::format("{} is {}x{} but the frame's image is {}x{}", what, image.cols,
                                  image.rows, size.width, size.height));
  }
  return image;
}

// Shared by both sources: dilation (the extractor's elliptic element) and the movable share.
FrameMask Finish(cv::Mat mask, std::string path, int dilate_px) {
  if (dilate_px > 0) {
    const int side = 2 * dilate_px + 1;
    cv::dilate(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(side, side)));
  }
  FrameMask result;
  result.fraction = static_cast<double>(cv::countNonZero(mask)) / static_cast<double>(mask.total());
  result.mask = std::move(mask);
  result.path = std::move(path);
  return result;
}

class NoMasks : public MaskSource {
 public:
  FrameMask MaskFor(const io::FrameEntry&, const cv::Size&) const override { return {}; }
  std::string Describe() const override { return "none"; }
};

class MaskFiles : public MaskSource {
 public:
  explicit MaskFiles(const MaskOptions& options) : options_(options) {
    RequireDirectory(options_.folder, "mask folder");
  }
  FrameMask MaskFor(const io::FrameEntry& frame, const cv::Size& size) const override {
    const std::string path = MaskPathFor(options_.folder, frame);
    std::error_code ec;
    if (!fs::exists(path, ec)) {
      if (options_.missing_empty) return {};
      ThrowInFile(path, fmt::format("mask of frame {} ({}) does not exist (--mask-missing empty "
                                    "runs such frames without a mask)",
                                    frame.index, frame.image_left));
    }
    cv::Mat mask = ReadLabelImage(path, size, "a mask") != 0;  // any non-zero value is movable
    return Finish(std::move(mask), path, options_.dilate_px);
  }
  std::string Describe() const override {
    return fmt::format("files {}{}{}", options_.folder,
                       options_.missing_empty ? " (missing = empty)" : "",
                       options_.dilate_px > 0 ? fmt::format(", dilated {} px", options_.dilate_px)
                                              : std::string());
  }

 private:
  MaskOptions options_;
};

// <root>/classes.txt; else beside the rgb/ folder of the first frame (an image-folder sequence
// read from rgb/ itself has that folder as its root).
std::string ClassesPath(const io::Sequence& sequence) {
  const fs::path at_root = fs::path(sequence.root) / "classes.txt";
  std::error_code ec;
  if (fs::exists(at_root, ec) || sequence.empty()) return at_root.string();
  const fs::path beside =
      fs::path(sequence.frames.front().image_left).parent_path().parent_path() / "classes.txt";
  return fs::exists(beside, ec) ? beside.string() : at_root.string();
}

class SynthGroundTruth : public MaskSource {
 public:
  SynthGroundTruth(const MaskOptions& options, const io::Sequence& sequence)
      : dilate_px_(options.dilate_px), lut_(1, 256, CV_8UC1, cv::Scalar(0)) {
    const std::string classes_path = ClassesPath(sequence);
    const std::vector<io::ClassInfo> classes = io::ReadClassList(classes_path);
    for (const std::string& name : options.movable) {
      const auto it = std::find_if(classes.begin(), classes.end(),
                                   [&](const io::ClassInfo& c) { return c.name == name; });
      if (it == classes.end()) {
        std::vector<std::string> known;
        for (const io::ClassInfo& c : classes) known.push_back(c.name);
        ThrowInFile(classes_path, fmt::format("--movable: no class named '{}' (classes: {})", name,
                                              fmt::join(known, ", ")));
      }
    }
    for (const io::ClassInfo& c : classes) {
      const bool movable = options.movable.empty()
                               ? c.movable
                               : std::find(options.movable.begin(), options.movable.end(),
                                           c.name) != options.movable.end();
      if (!movable) continue;
      lut_.at<uint8_t>(0, c.id) = 255;
      names_.push_back(c.name);
    }
    if (names_.empty()) spdlog::warn("{}: no class is movable; every mask is empty", classes_path);
  }
  FrameMask MaskFor(const io::FrameEntry& frame, const cv::Size& size) const override {
    // <dir>/rgb/<stem>.png -> <dir>/class/<stem>.png.
    const fs::path image(frame.image_left);
    const std::string path =
        (image.parent_path().parent_path() / "class" / image.stem()).string() + ".png";
    std::error_code ec;
    if (!fs::exists(path, ec)) {
      ThrowInFile(path, fmt::format("class image of frame {} ({}) does not exist", frame.index,
                                    frame.image_left));
    }
    cv::Mat mask;
    cv::LUT(ReadLabelImage(path, size, "a class image"), lut_, mask);
    return Finish(std::move(mask), path, dilate_px_);
  }
  std::string Describe() const override {
    return fmt::format("synth-gt (movable: {}){}", fmt::join(names_, ", "),
                       dilate_px_ > 0 ? fmt::format(", dilated {} px", dilate_px_) : std::string());
  }

 private:
  int dilate_px_;
  cv::Mat lut_;  // class id -> 255 for movable classes, 0 otherwise
  std::vector<std::string> names_;
};

}  // namespace

std::unique_ptr<MaskSource> MakeMaskSource(const MaskOptions& options,
                                           const io::Sequence& sequence) {
  options.Check();
  switch (options.kind) {
    case MaskSourceKind::kFiles:
      return std::make_unique<MaskFiles>(options);
    case MaskSourceKind::kSynthGt:
      return std::make_unique<SynthGroundTruth>(options, sequence);
    case MaskSourceKind::kOnnx:
    case MaskSourceKind::kDetector:
    case MaskSourceKind::kModel:
      return MakeModelMaskSource(options);
    case MaskSourceKind::kNone:
      break;
  }
  return std::make_unique<NoMasks>();
}

}  // namespace moslam::runner
