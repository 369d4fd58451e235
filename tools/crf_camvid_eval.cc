// Measures what the fully connected CRF does to a CNN's segmentation on CamVid: the binary
// "movable object" IoU (car, pedestrian, bicyclist) of DeepLabV3-MobileNetV2 (PASCAL VOC, through
// OpenCV dnn) before and after the CRF, accumulated over a split, and overlays of a few images.
//
//   build/tools/crf_camvid_eval --camvid ../shared/data/camvid --split val
//       --model ../shared/models/deeplabv3_mnv2_voc/deeplabv3_mnv2_voc.onnx --overlays out/
//
// The network's 21 VOC probabilities are the CRF's unaries (21 labels); the movable mask is the
// set of pixels whose label is a VOC class that moves (person, car, bus, bicycle, motorbike,
// aeroplane). A second CRF runs on 2 labels (movable: the sum of those classes' probabilities,
// vs. the rest). CamVid's pixel labels are used for evaluation only.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/semantic/dense_crf.h"
#include "moslam/semantic/overlay.h"
#include "moslam/util/error.h"
#include "moslam/util/log.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace {

using moslam::semantic::CrfResult;
using moslam::semantic::DenseCrf;
using moslam::semantic::DenseCrfOptions;
using moslam::semantic::Unaries;

// VOC classes that move: aeroplane 1, bicycle 2, bus 6, car 7, motorbike 14, person 15.
constexpr int kVocMovable[] = {1, 2, 6, 7, 14, 15};
constexpr int kVocClasses = 21;
constexpr int kNetworkSize = 513;
// CamVid: 8 Car, 9 Pedestrian, 10 Bicyclist are movable; 11 Unlabelled.
constexpr int kCamVidUnlabelled = 11;

bool IsVocMovable(int label) {
  for (int m : kVocMovable) {
    if (label == m) return true;
  }
  return false;
}

struct Iou {
  int64_t intersection = 0;
  int64_t union_ = 0;
  void Add(const cv::Mat& predicted, const cv::Mat& truth, const cv::Mat& valid) {
    intersection += cv::countNonZero(predicted & truth & valid);
    union_ += cv::countNonZero((predicted | truth) & valid);
  }
  double Value() const { return union_ == 0 ? 0.0 : static_cast<double>(intersection) / union_; }
};

// Softmax of the network's logits (1 x 21 x 513 x 513), resized to `size`: planar {21, H, W}.
cv::Mat Probabilities(const cv::Mat& logits, cv::Size size) {
  const int n = kNetworkSize * kNetworkSize;
  cv::Mat soft(kVocClasses, n, CV_32F);
  const float* in = logits.ptr<float>();
  for (int p = 0; p < n; ++p) {
    float top = in[p];
    for (int c = 1; c < kVocClasses; ++c) top = std::max(top, in[c * n + p]);
    float sum = 0.0f;
    for (int c = 0; c < kVocClasses; ++c) {
      const float e = std::exp(in[c * n + p] - top);
      soft.at<float>(c, p) = e;
      sum += e;
    }
    for (int c = 0; c < kVocClasses; ++c) soft.at<float>(c, p) /= sum;
  }
  const int sizes[3] = {kVocClasses, size.height, size.width};
  cv::Mat probs(3, sizes, CV_32F);
  for (int c = 0; c < kVocClasses; ++c) {
    const cv::Mat plane(kNetworkSize, kNetworkSize, CV_32F, soft.ptr<float>(c));
    cv::Mat out = moslam::semantic::LabelPlane(probs, c);
    // Bilinear interpolation keeps the per-pixel sums at 1.
    cv::resize(plane, out, size, 0, 0, cv::INTER_LINEAR);
  }
  return probs;
}

cv::Mat ArgMax(const cv::Mat& probs) {
  cv::Mat labels(probs.size[1], probs.size[2], CV_8U, cv::Scalar(0));
  cv::Mat best = moslam::semantic::LabelPlane(probs, 0).clone();
  for (int c = 1; c < probs.size[0]; ++c) {
    const cv::Mat plane = moslam::semantic::LabelPlane(probs, c);
    const cv::Mat better = plane > best;
    labels.setTo(c, better);
    plane.copyTo(best, better);
  }
  return labels;
}

cv::Mat MovableMask(const cv::Mat& voc_labels) {
  cv::Mat mask(voc_labels.size(), CV_8U, cv::Scalar(0));
  for (int m : kVocMovable) mask |= (voc_labels == m);
  return mask;
}

// Planar {2, H, W}: label 1 = the movable classes' total probability.
cv::Mat BinaryProbabilities(const cv::Mat& probs) {
  const int sizes[3] = {2, probs.size[1], probs.size[2]};
  cv::Mat binary(3, sizes, CV_32F, cv::Scalar(0));
  cv::Mat movable = moslam::semantic::LabelPlane(binary, 1);
  for (int c = 0; c < kVocClasses; ++c) {
    if (IsVocMovable(c)) movable += moslam::semantic::LabelPlane(probs, c);
  }
  cv::Mat rest = moslam::semantic::LabelPlane(binary, 0);
  cv::subtract(cv::Scalar(1.0), movable, rest);
  return binary;
}

struct Entry {
  std::string image;
  std::string labels;
};

std::vector<Entry> ReadSplit(const std::string& camvid, const std::string& split) {
  const std::string list = camvid + "/" + split + ".txt";
  std::vector<Entry> entries;
  for (const moslam::TextLine& line : moslam::ReadDataLines(list)) {
    const auto fields = moslam::SplitFields(line.text);
    if (fields.size() != 2) moslam::ThrowAtLine(list, line.number, "expected: IMAGE LABELS");
    // Lines name files relative to the folder that holds the list (SegNet's own list uses
    // absolute paths ending in the same relative part).
    const auto relative = [](std::string_view path) {
      const std::filesystem::path p{std::string(path)};
      return (p.parent_path().filename() / p.filename()).string();
    };
    entries.push_back({camvid + "/" + relative(fields[0]), camvid + "/" + relative(fields[1])});
  }
  return entries;
}

// One image with the network's probabilities and the ground truth.
struct Sample {
  std::string name;
  cv::Mat image;
  cv::Mat probs;     // planar {21, H, W}
  cv::Mat truth;     // movable, 255 = yes
  cv::Mat labelled;  // not Unlabelled
};

// Planes averaged over blocks of `factor` pixels and interpolated back: the blurry, blocky
// probabilities of a coarser network (or of class activation maps, as in weak supervision).
void Coarsen(int factor, cv::Mat* probs) {
  for (int c = 0; c < probs->size[0]; ++c) {
    cv::Mat plane = moslam::semantic::LabelPlane(*probs, c);
    cv::Mat small;
    cv::resize(plane, small, cv::Size(), 1.0 / factor, 1.0 / factor, cv::INTER_AREA);
    cv::resize(small, plane, plane.size(), 0, 0, cv::INTER_LINEAR);
  }
}

Sample LoadSample(const Entry& entry, cv::dnn::Net& net, int coarse, double* network_ms) {
  Sample s;
  s.name = std::filesystem::path(entry.image).stem().string();
  s.image = cv::imread(entry.image, cv::IMREAD_COLOR);
  const cv::Mat annotation = cv::imread(entry.labels, cv::IMREAD_GRAYSCALE);
  if (s.image.empty()) moslam::ThrowInFile(entry.image, "cannot be read as an image");
  if (annotation.size() != s.image.size()) {
    moslam::ThrowInFile(entry.labels, "missing or not the size of its image");
  }
  const auto start = std::chrono::steady_clock::now();
  // RGB in [-1, 1] at 513 x 513.
  net.setInput(cv::dnn::blobFromImage(s.image, 1.0 / 127.5, cv::Size(kNetworkSize, kNetworkSize),
                                      cv::Scalar(127.5, 127.5, 127.5), /*swapRB=*/true));
  s.probs = Probabilities(net.forward(), s.image.size());
  if (coarse > 1) Coarsen(coarse, &s.probs);
  *network_ms +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  s.truth = (annotation >= 8) & (annotation <= 10);
  s.labelled = annotation != kCamVidUnlabelled;
  return s;
}

// Accumulated IoUs over a set of images.
struct Scores {
  Iou before;      // DeepLab's argmax
  Iou after;       // CRF on the 21 VOC labels
  Iou binary;      // CRF on 2 labels (movable or not)
  Iou before_all;  // the same two counting Unlabelled pixels too
  Iou after_all;
  double crf_ms = 0.0;
};

void Score(const Sample& s, DenseCrf& crf, bool binary, Scores* scores, cv::Mat* mask_before,
           cv::Mat* mask_after) {
  CrfResult result;
  const auto start = std::chrono::steady_clock::now();
  crf.Infer(s.image, cv::Mat(), Unaries::FromProbabilities(s.probs), &result);
  scores->crf_ms +=
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  *mask_before = MovableMask(ArgMax(s.probs));
  *mask_after = MovableMask(result.labels);
  const cv::Mat everywhere(s.truth.size(), CV_8U, cv::Scalar(255));
  scores->before.Add(*mask_before, s.truth, s.labelled);
  scores->after.Add(*mask_after, s.truth, s.labelled);
  scores->before_all.Add(*mask_before, s.truth, everywhere);
  scores->after_all.Add(*mask_after, s.truth, everywhere);
  if (binary) {
    crf.Infer(s.image, cv::Mat(), Unaries::FromProbabilities(BinaryProbabilities(s.probs)),
              &result);
    scores->binary.Add(result.labels != 0, s.truth, s.labelled);
  }
}

void WriteOverlays(const Sample& s, const cv::Mat& mask_before, const cv::Mat& mask_after,
                   const cv::Mat& labels_before, const cv::Mat& labels_after,
                   const std::string& folder) {
  const cv::Scalar red(0, 0, 255);
  cv::imwrite(folder + "/" + s.name + "_movable.png",
              moslam::semantic::SideBySide(
                  {moslam::semantic::DrawMaskOverlay(s.image, s.truth, cv::Scalar(0, 200, 0)),
                   moslam::semantic::DrawMaskOverlay(s.image, mask_before, red),
                   moslam::semantic::DrawMaskOverlay(s.image, mask_after, red)},
                  {"CamVid movable (truth)", "DeepLab", "DeepLab + CRF"}));
  cv::imwrite(
      folder + "/" + s.name + "_labels.png",
      moslam::semantic::SideBySide({moslam::semantic::DrawLabelOverlay(s.image, labels_before),
                                    moslam::semantic::DrawLabelOverlay(s.image, labels_after)},
                                   {"DeepLab VOC labels", "after CRF"}));
}

// A small grid over the kernel weights and the appearance kernel's widths, evaluated on images
// cached in memory; prints one line per setting and the best.
void Tune(const std::vector<Sample>& samples, const DenseCrfOptions& base) {
  struct Setting {
    DenseCrfOptions options;
    double iou = 0.0;
  };
  std::vector<Setting> settings;
  // (A first, wider grid on 40 train images, appearance weights up to 10 and sxy up to 80,
  // found larger weights and widths only lowering the IoU.)
  for (float smoothness : {0.0f, 1.0f, 3.0f}) {
    for (float weight : {0.0f, 1.0f, 3.0f}) {
      for (float srgb : {3.0f, 5.0f}) {
        for (float sxy : {5.0f, 10.0f, 20.0f}) {
          if ((smoothness == 0.0f && weight == 0.0f) ||
              (weight == 0.0f && (srgb != 3.0f || sxy != 5.0f))) {
            continue;  // no CRF, or the same setting again
          }
          Setting s{base};
          s.options.smoothness_weight = smoothness;
          s.options.appearance_weight = weight;
          s.options.appearance_srgb = srgb;
          s.options.appearance_sxy = sxy;
          settings.push_back(s);
        }
      }
    }
  }
  for (Setting& setting : settings) {
    DenseCrf crf(setting.options);
    Scores scores;
    cv::Mat before;
    cv::Mat after;
    for (const Sample& s : samples) Score(s, crf, false, &scores, &before, &after);
    setting.iou = scores.after.Value();
    const DenseCrfOptions& o = setting.options;
    std::printf(
        "smoothness_weight %.0f appearance_weight %.0f appearance_srgb %4.1f "
        "appearance_sxy %4.1f: %.4f (without CRF %.4f)\n",
        o.smoothness_weight, o.appearance_weight, o.appearance_srgb, o.appearance_sxy, setting.iou,
        scores.before.Value());
    std::fflush(stdout);
  }
  const Setting& best =
      *std::max_element(settings.begin(), settings.end(),
                        [](const Setting& a, const Setting& b) { return a.iou < b.iou; });
  std::printf(
      "best: smoothness_weight %.0f appearance_weight %.0f appearance_srgb %.1f "
      "appearance_sxy %.1f: %.4f\n",
      best.options.smoothness_weight, best.options.appearance_weight, best.options.appearance_srgb,
      best.options.appearance_sxy, best.iou);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Movable-object IoU on CamVid of DeepLab's probabilities before and after the CRF"};
  std::string camvid = "../shared/data/camvid";
  std::string split = "val";
  std::string model = "../shared/models/deeplabv3_mnv2_voc/deeplabv3_mnv2_voc.onnx";
  std::string config;
  std::string overlays;
  int limit = 0;
  int overlay_every = 20;
  int threads = 2;
  int tune = 0;
  int coarse = 1;
  std::string log_level = "info";
  app.add_option("--camvid", camvid, "CamVid folder (SegNet layout)")->capture_default_str();
  app.add_option("--split", split, "List to evaluate: val, train or test")->capture_default_str();
  app.add_option("--model", model, "DeepLabV3 ONNX model (VOC, 513x513)")->capture_default_str();
  app.add_option("--config", config, "YAML file with crf.* options (default: the defaults)");
  app.add_option("--threads", threads, "CRF threads")->capture_default_str();
  app.add_option("--limit", limit, "Evaluate only the first N images (0: all)")
      ->capture_default_str();
  app.add_option("--overlays", overlays, "Folder for before/after overlay PNGs");
  app.add_option("--overlay-every", overlay_every, "Write overlays for every N-th image")
      ->capture_default_str();
  app.add_option("--tune", tune,
                 "Instead of evaluating, try a grid of appearance-kernel settings on N images "
                 "spread over the split (use the train split, then evaluate val with the best)")
      ->capture_default_str();
  app.add_option("--coarse", coarse,
                 "Average the probabilities over blocks of N x N pixels first (1: off), to see "
                 "the CRF on coarse unaries")
      ->capture_default_str();
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  try {
    moslam::SetupLogging(log_level);
    DenseCrfOptions options =
        config.empty() ? DenseCrfOptions() : moslam::semantic::LoadDenseCrfOptions(config);
    options.num_threads = threads;
    std::vector<Entry> entries = ReadSplit(camvid, split);
    if (limit > 0 && static_cast<size_t>(limit) < entries.size()) entries.resize(limit);
    moslam::RequireFile(model, "DeepLab model");
    cv::dnn::Net net = cv::dnn::readNetFromONNX(model);
    double network_ms = 0.0;

    if (tune > 0) {
      std::vector<Sample> samples;
      const size_t count = std::min(entries.size(), static_cast<size_t>(tune));
      for (size_t i = 0; i < count; ++i) {
        samples.push_back(
            LoadSample(entries[i * entries.size() / count], net, coarse, &network_ms));
      }
      std::printf("tuning on %zu images of %s\n", samples.size(), split.c_str());
      Tune(samples, options);
      return 0;
    }

    if (!overlays.empty()) std::filesystem::create_directories(overlays);
    DenseCrf crf(options);
    Scores scores;
    for (size_t i = 0; i < entries.size(); ++i) {
      const Sample s = LoadSample(entries[i], net, coarse, &network_ms);
      cv::Mat mask_before;
      cv::Mat mask_after;
      Score(s, crf, true, &scores, &mask_before, &mask_after);
      if (!overlays.empty() && overlay_every > 0 && i % overlay_every == 0) {
        const CrfResult result = crf.Infer(s.image, cv::Mat(), Unaries::FromProbabilities(s.probs));
        WriteOverlays(s, mask_before, mask_after, ArgMax(s.probs), result.labels, overlays);
      }
      spdlog::debug("{}: IoU so far {:.4f} -> {:.4f}", s.name, scores.before.Value(),
                    scores.after.Value());
    }
    const double n = static_cast<double>(entries.size());
    std::printf("CamVid %s, %zu images, binary movable IoU (accumulated over the split)%s\n",
                split.c_str(), entries.size(),
                coarse > 1
                    ? fmt::format(", probabilities averaged over {0}x{0} blocks", coarse).c_str()
                    : "");
    std::printf(
        "  ignoring Unlabelled pixels: DeepLab %.4f, + CRF (21 labels) %.4f, "
        "+ CRF (2 labels) %.4f\n",
        scores.before.Value(), scores.after.Value(), scores.binary.Value());
    std::printf("  all pixels:                 DeepLab %.4f, + CRF (21 labels) %.4f\n",
                scores.before_all.Value(), scores.after_all.Value());
    std::printf("  time per image: network %.1f ms, CRF (21 + 2 labels, %d threads) %.1f ms\n",
                network_ms / n, threads, scores.crf_ms / n);
  } catch (const moslam::InputError& e) {
    spdlog::error("{}", e.what());
    return 2;
  } catch (const cv::Exception& e) {
    spdlog::error("OpenCV: {}", e.what());
    return 3;
  }
  return 0;
}
