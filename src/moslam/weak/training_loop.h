// Shared machinery of the training loops (training.h): epoch and batch scheduling, the learning
// rate schedule, progress lines, per-epoch history, checkpoints and the training-curve image.
// Internal to weak/.
#pragma once

#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <torch/torch.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "moslam/net/networks.h"
#include "moslam/weak/training.h"

namespace moslam::weak::internal {

// What one optimization step reports: the loss (and named parts of it) and, for accuracy,
// `correct` out of `count` predictions.
struct StepStats {
  double loss = 0.0;
  std::map<std::string, double> parts;
  double correct = 0.0;
  double count = 0.0;
  int images = 0;
};

struct EpochRecord {
  int epoch = 0;  // 1-based
  double loss = 0.0;
  double accuracy = 0.0;  // NaN when the step reports no predictions
  std::map<std::string, double> parts;
  double images_per_s = 0.0;
  double seconds = 0.0;
};

nlohmann::json ToJson(const std::vector<EpochRecord>& history);
std::vector<EpochRecord> HistoryFromJson(const nlohmann::json& json);

// The training curve: loss (and its parts) per epoch on the left axis, accuracy on the right.
cv::Mat RenderTrainingCurve(const std::vector<EpochRecord>& history, const std::string& title);

// Adam with two parameter groups: the pretrained backbone at lr * backbone_lr_factor, the new
// layers at lr. Only parameters that require gradients are given to the optimizer.
std::unique_ptr<torch::optim::Adam> MakeOptimizer(torch::nn::Module& backbone,
                                                  torch::nn::Module& whole,
                                                  const CommonTrainOptions& options);

// Polynomial decay (DeepLab's "poly" policy, power 0.9) of every group's initial rate.
void SetPolyLearningRate(torch::optim::Adam& optimizer, const std::vector<double>& initial,
                         int64_t step, int64_t total_steps);

// One optimization step on the images `indices` (already shuffled into a batch).
using StepFunction =
    std::function<StepStats(const std::vector<int>& indices, std::mt19937_64& rng)>;

struct LoopSpec {
  std::string name;  // "classifier (colour)", for progress lines and the curve's title
  int num_images = 0;
  torch::nn::Module* net = nullptr;
  const net::NetConfig* config = nullptr;
  torch::optim::Adam* optimizer = nullptr;
  StepFunction step;
  // Writes the final model file (called once after the last epoch).
  std::function<void(const std::string& path)> save_model;
};

// Runs epochs from the checkpoint's epoch (when resuming) to options.epochs, shuffling with a
// generator seeded by (seed, epoch) so that a resumed run sees the same batches. Writes
// out/checkpoint.mnet after every epoch, out/curve.png, out/history.json and, at the end,
// out/model.mnet. Returns the summary.
TrainSummary RunTrainingLoop(const CommonTrainOptions& options, const LoopSpec& spec);

// The training list of `options.data`, cut to options.max_images when that is set.
ImageList LoadTrainingList(const CommonTrainOptions& options);

// Writes out/report.json: the kind, model path, network configuration, data size, epochs, final
// loss and run time, plus `extra` (the loop's own options), and logs where the model went.
void WriteReport(const CommonTrainOptions& options, const std::string& kind,
                 const TrainSummary& summary, const net::NetConfig& config, size_t images,
                 const nlohmann::json& extra = nlohmann::json::object());

// Creates `folder` (and parents); InputError when it cannot.
void MakeFolder(const std::string& folder);

}  // namespace moslam::weak::internal

namespace moslam::weak::internal {

// Class activation maps of `net` for an image already at the network's input size (CV_8UC3 BGR):
// {C, H, W} CV_32F at the image's size (bilinear upsampling of the stride-s maps). `scores`
// receives the sigmoid class scores when not null.
cv::Mat ComputeCams(net::ClassifierNet& net, const cv::Mat& image, std::vector<float>* scores);

// The mean over views of `image` (CV_8UC3 BGR): the image resized by each of `scales` and, with
// `flip`, its mirror images. `map` takes a 1 x 3 x h x w input tensor of a view (on `device`) and
// returns a 1 x C x h' x w' map; each map is mirrored back, upsampled bilinearly to the image's
// size and passed through `activation` before the mean, which is 1 x C x H x W.
torch::Tensor MeanOverViews(const cv::Mat& image, const std::vector<double>& scales, bool flip,
                            torch::Device device,
                            const std::function<torch::Tensor(const torch::Tensor&)>& map,
                            const std::function<torch::Tensor(const torch::Tensor&)>& activation);

// Multi-scale CAMs, as WSSS methods take them (e.g. Ahn and Kwak, CVPR 2018): the mean of the
// ReLU'd CAMs of `image` resized by each of `scales` and, with `flip`, of their mirror images,
// each upsampled to the image's size ({C, H, W} CV_32F). A larger scale resolves objects that
// are a few pixels of the stride-16 map wide. scales {1} without flip equals ReLU(ComputeCams).
cv::Mat AugmentedCams(net::ClassifierNet& net, const cv::Mat& image,
                      const std::vector<double>& scales, bool flip);

// The segmenter's softmax on `image` (CV_8UC3 BGR at the network's input size), C x H x W at
// the image's size: the mean over the image resized by each of `scales` and, with `flip`, their
// mirror images (CueGenerationOptions::scales).
torch::Tensor AugmentedProbabilities(net::SegmenterNet& net, const cv::Mat& image,
                                     const std::vector<double>& scales, bool flip);

// Where training runs: the first CUDA device when libtorch sees one, else the CPU (logged).
torch::Device TrainingDevice();

// Side-by-side panels with captions (for preview images); all panels are resized to the first's
// height.
cv::Mat SideBySide(const std::vector<cv::Mat>& panels, const std::vector<std::string>& captions);

}  // namespace moslam::weak::internal
