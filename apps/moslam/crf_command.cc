// moslam crf: refines a per-pixel class-probability map of one image with the fully connected
// CRF (semantic/dense_crf.h) and writes the result as an overlay, to try kernels and settings.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "moslam/semantic/dense_crf.h"
#include "moslam/semantic/overlay.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam::app {
namespace {

using semantic::DenseCrfOptions;

struct CrfArgs {
  std::string image;
  std::string probs;
  std::string depth;
  double depth_scale = 5000.0;
  std::string kernels = "c";
  std::string config;
  float gt_prob = 0.7f;
  int num_labels = 0;
  std::string out;
  std::string labels_out;
  DenseCrfOptions options;
};

// The value of `key` in a .npy header dict ("{'descr': '<f4', 'fortran_order': False, ...}").
std::string NpyField(const std::string& header, const std::string& key, const std::string& path) {
  const size_t at = header.find("'" + key + "'");
  if (at == std::string::npos) ThrowInFile(path, "npy header has no '" + key + "'");
  const size_t colon = header.find(':', at);
  size_t end = colon + 1;
  if (header.find('(', colon) == header.find_first_not_of(' ', colon + 1)) {
    end = header.find(')', colon) + 1;
  } else {
    end = header.find_first_of(",}", colon);
  }
  return std::string(Trim(header.substr(colon + 1, end - colon - 1)));
}

// The CRF's own checks of the probabilities (2..32 labels, finite, the image's size) know no
// file; its InputErrors are the probabilities file's (issue 31).
semantic::CrfResult InferNamingFiles(semantic::DenseCrf& crf, const cv::Mat& image,
                                     const cv::Mat& depth, const cv::Mat& probs,
                                     const CrfArgs& args) {
  try {
    return crf.Infer(image, depth, semantic::Unaries::FromProbabilities(probs));
  } catch (const InputError& e) {
    ThrowInFile(args.probs, fmt::format("{} (image {})", e.what(), args.image));
  }
}

// A NumPy .npy array of float32 or float64, C order, shape (H, W, L): H x W CV_32FC(L).
cv::Mat ReadNpy(const std::string& path) {
  RequireFile(path, "probabilities");
  std::ifstream in(path, std::ios::binary);
  char magic[8];
  if (!in.read(magic, 8) || std::memcmp(magic, "\x93NUMPY", 6) != 0) {
    ThrowInFile(path, "is not a .npy file");
  }
  uint32_t header_size = 0;
  if (magic[6] == 1) {
    uint8_t size[2];
    in.read(reinterpret_cast<char*>(size), 2);
    header_size = size[0] | (size[1] << 8);
  } else {
    uint8_t size[4];
    in.read(reinterpret_cast<char*>(size), 4);
    header_size =
        size[0] | (size[1] << 8) | (size[2] << 16) | (static_cast<uint32_t>(size[3]) << 24);
  }
  std::string header(header_size, '\0');
  if (!in.read(header.data(), header_size)) ThrowInFile(path, "truncated npy header");
  const std::string descr = NpyField(header, "descr", path);
  if (NpyField(header, "fortran_order", path) != "False") {
    ThrowInFile(path, "npy arrays in Fortran order are not supported; save with C order");
  }
  std::string shape = NpyField(header, "shape", path);
  shape = shape.substr(1, shape.size() - 2);  // strip the parentheses
  std::vector<int> dims;
  for (std::string_view field : SplitFields(shape, true)) {
    const auto value = ParseInt(std::string(field));
    if (!value || *value <= 0) ThrowInFile(path, "bad npy shape (" + shape + ")");
    dims.push_back(*value);
  }
  if (dims.size() != 3) {
    ThrowInFile(path, "expected an H x W x L array, got shape (" + shape + ")");
  }
  const bool f4 = descr == "'<f4'";
  const bool f8 = descr == "'<f8'";
  if (!f4 && !f8) ThrowInFile(path, "expected float32 or float64 data, got " + descr);
  if (dims[2] > CV_CN_MAX) ThrowInFile(path, "too many labels");
  cv::Mat data(dims[0], dims[1], CV_MAKETYPE(f4 ? CV_32F : CV_64F, dims[2]));
  const auto bytes = static_cast<std::streamsize>(data.total() * data.elemSize());
  if (!in.read(reinterpret_cast<char*>(data.data), bytes)) ThrowInFile(path, "truncated npy data");
  if (f8) data.convertTo(data, CV_MAKETYPE(CV_32F, dims[2]));
  return data;
}

// A label image turned into probabilities: `p` for the pixel's label, the rest shared evenly;
// label 255 (VOC's "ignore") is uniform.
cv::Mat ProbabilitiesFromLabels(const std::string& path, int num_labels, float p) {
  const cv::Mat labels = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (labels.empty()) ThrowInFile(path, "cannot be read as a label image");
  if (num_labels == 0) {
    double top = 0.0;
    cv::minMaxLoc(labels, nullptr, &top, nullptr, nullptr, labels != 255);
    num_labels = std::max(2, static_cast<int>(top) + 1);
  }
  if (num_labels < 2 || num_labels > 32) {
    ThrowInFile(path, fmt::format("as a label image it needs {} labels; 2 to 32 are supported "
                                  "(set --num-labels, or give a .npy)",
                                  num_labels));
  }
  if (!(p > 0.0f && p < 1.0f)) ThrowInput("--gt-prob must be in (0, 1)");
  const int sizes[3] = {num_labels, labels.rows, labels.cols};
  cv::Mat probs(3, sizes, CV_32F);
  const float other = (1.0f - p) / static_cast<float>(num_labels - 1);
  for (int y = 0; y < labels.rows; ++y) {
    for (int x = 0; x < labels.cols; ++x) {
      const int label = labels.at<uint8_t>(y, x);
      if (label != 255 && label >= num_labels) {
        ThrowInFile(path, fmt::format("label {} at ({}, {}) is not below --num-labels {}", label, x,
                                      y, num_labels));
      }
      for (int l = 0; l < num_labels; ++l) {
        probs.at<float>(l, y, x) =
            label == 255 ? 1.0f / static_cast<float>(num_labels) : (l == label ? p : other);
      }
    }
  }
  return probs;
}

// Depth in metres: a 16-bit image divided by `scale`, or a 32-bit float image as it is.
cv::Mat ReadDepth(const std::string& path, double scale) {
  const cv::Mat raw = cv::imread(path, cv::IMREAD_ANYDEPTH);
  if (raw.empty()) ThrowInFile(path, "cannot be read as a depth image");
  cv::Mat metres;
  if (raw.type() == CV_16UC1) {
    raw.convertTo(metres, CV_32F, 1.0 / scale);
  } else if (raw.type() == CV_32FC1) {
    metres = raw;
  } else {
    ThrowInFile(path, "depth must be a 16-bit or a 32-bit float single-channel image");
  }
  return metres;
}

cv::Mat ArgMax(const cv::Mat& planar) {
  cv::Mat labels(planar.size[1], planar.size[2], CV_8U, cv::Scalar(0));
  cv::Mat best = semantic::LabelPlane(planar, 0).clone();
  for (int l = 1; l < planar.size[0]; ++l) {
    const cv::Mat plane = semantic::LabelPlane(planar, l);
    const cv::Mat better = plane > best;
    labels.setTo(l, better);
    plane.copyTo(best, better);
  }
  return labels;
}

// Planar {L, H, W} from planar or interleaved probabilities.
cv::Mat ToPlanar(const cv::Mat& probs) {
  if (probs.dims == 3) return probs;
  std::vector<cv::Mat> planes;
  cv::split(probs, planes);
  const int sizes[3] = {probs.channels(), probs.rows, probs.cols};
  cv::Mat planar(3, sizes, CV_32F);
  for (int l = 0; l < probs.channels(); ++l) planes[l].copyTo(semantic::LabelPlane(planar, l));
  return planar;
}

void Run(CrfArgs args) {
  const cv::Mat image = cv::imread(args.image, cv::IMREAD_UNCHANGED);
  if (image.empty()) ThrowInFile(args.image, "cannot be read as an image");
  cv::Mat image8;
  if (image.depth() != CV_8U) ThrowInFile(args.image, "must be an 8-bit image");
  if (image.channels() == 4) {
    cv::cvtColor(image, image8, cv::COLOR_BGRA2BGR);
  } else {
    image8 = image;
  }
  const bool npy = EndsWith(ToLower(args.probs), ".npy");
  const cv::Mat probs = npy ? ReadNpy(args.probs)
                            : ProbabilitiesFromLabels(args.probs, args.num_labels, args.gt_prob);
  DenseCrfOptions& o = args.options;
  o.smoothness = true;
  o.appearance = args.kernels == "c" || args.kernels == "cd";
  o.depth = args.kernels == "d" || args.kernels == "cd";
  cv::Mat depth;
  if (o.depth) {
    if (args.depth.empty()) ThrowInput("--kernels {} needs --depth", args.kernels);
    depth = ReadDepth(args.depth, args.depth_scale);
  } else if (!args.depth.empty()) {
    spdlog::warn("--depth is ignored with --kernels c");
  }
  semantic::DenseCrf crf(o);
  const auto start = std::chrono::steady_clock::now();
  const semantic::CrfResult result = InferNamingFiles(crf, image8, depth, probs, args);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const cv::Mat before = ArgMax(ToPlanar(probs));
  const cv::Mat panels = semantic::SideBySide({semantic::DrawLabelOverlay(image8, before),
                                               semantic::DrawLabelOverlay(image8, result.labels)},
                                              {"input (argmax)", "CRF " + args.kernels});
  if (!cv::imwrite(args.out, panels)) ThrowInFile(args.out, "cannot be written");
  if (!args.labels_out.empty() && !cv::imwrite(args.labels_out, result.labels)) {
    ThrowInFile(args.labels_out, "cannot be written");
  }
  const int changed = cv::countNonZero(before != result.labels);
  std::printf("%dx%d, %d labels, kernels %s: %d pixels (%.2f%%) changed label, %.1f ms\n",
              image8.cols, image8.rows, probs.channels(), args.kernels.c_str(), changed,
              100.0 * changed / static_cast<double>(before.total()), ms);
}

}  // namespace

void AddCrfCommand(CLI::App& app) {
  auto args = std::make_shared<CrfArgs>();
  CLI::App* cmd = app.add_subcommand(
      "crf",
      "Refine a class-probability map with the fully connected CRF (Kraehenbuehl and Koltun 2011; "
      "depth kernel after Sun et al. 2019) and write before/after overlays.\n"
      "PROBS is either a NumPy .npy float32/float64 array of shape H x W x L (L = 2..32 "
      "classes, C order), or a label image (8-bit PNG, label per pixel, 255 = unknown) turned "
      "into probabilities with --gt-prob.");
  cmd->add_option("IMAGE", args->image, "Colour or grey 8-bit image")->required();
  cmd->add_option("PROBS", args->probs, "Probabilities (.npy, H x W x L) or label image")
      ->required();
  cmd->add_option("--out", args->out, "Overlay PNG: input labels | CRF labels")->required();
  cmd->add_option("--labels-out", args->labels_out, "CRF labels as an 8-bit PNG");
  cmd->add_option("--depth", args->depth,
                  "Depth image: 16-bit (divided by --depth-scale) or 32-bit float in metres; "
                  "0 = invalid");
  cmd->add_option("--depth-scale", args->depth_scale,
                  "Units per metre of a 16-bit depth image (5000: TUM RGB-D)")
      ->capture_default_str();
  cmd->add_option("--kernels", args->kernels,
                  "Pairwise kernels besides smoothness: c = appearance (colour), d = depth, "
                  "cd = both (the paper's c, d and c,d)")
      ->check(CLI::IsMember({"c", "d", "cd"}))
      ->capture_default_str();
  cmd->add_option("--config", args->config, "YAML file with crf.* options; flags override it");
  cmd->add_option("--gt-prob", args->gt_prob, "For a label image: probability of the pixel's label")
      ->capture_default_str();
  cmd->add_option("--num-labels", args->num_labels,
                  "For a label image: number of labels (0: largest label + 1)")
      ->capture_default_str();
  // CRF options, defaults shown; a given flag overrides --config.
  struct FloatFlag {
    const char* name;
    float DenseCrfOptions::*field;
    const char* help;
  };
  static const FloatFlag kFloatFlags[] = {
      {"--smoothness-sxy", &DenseCrfOptions::smoothness_sxy, "Smoothness kernel sigma, pixels"},
      {"--smoothness-weight", &DenseCrfOptions::smoothness_weight, "Smoothness kernel weight"},
      {"--appearance-sxy", &DenseCrfOptions::appearance_sxy, "Appearance kernel sigma, pixels"},
      {"--appearance-srgb", &DenseCrfOptions::appearance_srgb,
       "Appearance kernel sigma, intensity levels"},
      {"--appearance-weight", &DenseCrfOptions::appearance_weight, "Appearance kernel weight"},
      {"--depth-sxy", &DenseCrfOptions::depth_sxy, "Depth kernel sigma, pixels"},
      {"--depth-sd", &DenseCrfOptions::depth_sd_m, "Depth kernel sigma, metres"},
      {"--depth-weight", &DenseCrfOptions::depth_weight, "Depth kernel weight"}};
  auto flags = std::make_shared<DenseCrfOptions>();  // parsed flag values
  std::vector<std::pair<CLI::Option*, float DenseCrfOptions::*>> given;
  for (const FloatFlag& f : kFloatFlags) {
    given.emplace_back(cmd->add_option(f.name, (*flags).*(f.field), f.help)->capture_default_str(),
                       f.field);
  }
  CLI::Option* iterations =
      cmd->add_option("--iterations", flags->iterations, "Mean-field iterations")
          ->capture_default_str();
  CLI::Option* threads =
      cmd->add_option("--threads", flags->num_threads, "Threads")->capture_default_str();
  cmd->callback([args, flags, given, iterations, threads] {
    DenseCrfOptions& o = args->options;
    o = args->config.empty() ? DenseCrfOptions() : semantic::LoadDenseCrfOptions(args->config);
    for (const auto& [option, field] : given) {
      if (option->count() > 0) o.*field = (*flags).*field;
    }
    if (iterations->count() > 0) o.iterations = flags->iterations;
    if (threads->count() > 0) o.num_threads = flags->num_threads;
    Run(*args);
  });
}

}  // namespace moslam::app
