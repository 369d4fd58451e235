// One file per trained network (`.mnet`, a libtorch archive): the NetConfig as JSON, the weights,
// and, for training checkpoints, the optimizer state and the trainer's own state (epoch, history)
// so that an interrupted training resumes where it stopped. A shipped model is a model file plus
// a YAML model card beside it (semantic/model_card.h, `type: torch`).
#pragma once

#include <string>

#include <torch/torch.h>
#include <nlohmann/json.hpp>

#include "moslam/net/networks.h"

namespace moslam::net {

// Weights are stored as float16 when `half` is true (half the size; the networks run in float32
// after loading, and the rounding is far below what changes a prediction).
void SaveClassifier(const std::string& path, ClassifierNet& net, bool half = false);
void SaveSegmenter(const std::string& path, SegmenterNet& net, bool half = false);
// InputError when the file is missing, not a model file, or of the other kind.
ClassifierNet LoadClassifier(const std::string& path);
SegmenterNet LoadSegmenter(const std::string& path);
NetConfig ReadNetConfig(const std::string& path);

// Training checkpoint: a model file plus the optimizer and `trainer_state` (free-form JSON: epoch,
// step, RNG seed, loss history). Written to a temporary name and renamed, so an interruption
// never leaves a truncated checkpoint.
void SaveCheckpoint(const std::string& path, torch::nn::Module& net, const NetConfig& config,
                    torch::optim::Optimizer& optimizer, const nlohmann::json& trainer_state);
// Loads weights into `net` (built from the checkpoint's config by the caller) and the optimizer
// state; returns trainer_state.
nlohmann::json LoadCheckpoint(const std::string& path, torch::nn::Module& net,
                              torch::optim::Optimizer& optimizer);

}  // namespace moslam::net
