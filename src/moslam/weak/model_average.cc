#include "moslam/weak/model_average.h"

#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "moslam/net/model_file.h"
#include "moslam/util/error.h"

namespace moslam::weak {
namespace {

namespace fs = std::filesystem;

// Adds `from`'s floating-point tensors to `into`'s, by name (both built from the same config, so
// the names and shapes agree).
void Accumulate(torch::OrderedDict<std::string, torch::Tensor> into,
                const torch::OrderedDict<std::string, torch::Tensor>& from) {
  for (auto& item : into) {
    if (!item.value().is_floating_point()) continue;
    item.value().add_(from[item.key()]);
  }
}

void Scale(torch::OrderedDict<std::string, torch::Tensor> tensors, double factor) {
  for (auto& item : tensors) {
    if (item.value().is_floating_point()) item.value().mul_(factor);
  }
}

}  // namespace

net::SegmenterNet AverageSegmenters(const std::vector<std::string>& paths) {
  if (paths.size() < 2)
    ThrowInput("model averaging: give at least two models, got {}", paths.size());
  net::SegmenterNet sum = net::LoadSegmenter(paths[0]);
  const nlohmann::json config = net::ToJson(sum->config());
  torch::NoGradGuard no_grad;
  for (size_t i = 1; i < paths.size(); ++i) {
    net::SegmenterNet other = net::LoadSegmenter(paths[i]);
    if (net::ToJson(other->config()) != config) {
      ThrowInFile(paths[i], fmt::format("its network differs from {}'s ({} against {})", paths[0],
                                        net::ToJson(other->config()).dump(), config.dump()));
    }
    Accumulate(sum->named_parameters(), other->named_parameters());
    Accumulate(sum->named_buffers(), other->named_buffers());
  }
  const double factor = 1.0 / static_cast<double>(paths.size());
  Scale(sum->named_parameters(), factor);
  Scale(sum->named_buffers(), factor);
  return sum;
}

void AverageOptions::Check() const {
  if (models.size() < 2)
    ThrowInput("--models: give at least two model files, got {}", models.size());
  if (out.empty()) ThrowInput("--out: an output folder is required");
}

void AverageSegmenterFiles(const AverageOptions& options) {
  options.Check();
  net::SegmenterNet average = AverageSegmenters(options.models);
  fs::create_directories(options.out);
  const std::string model = (fs::path(options.out) / "model.mnet").string();
  net::SaveSegmenter(model, average, options.half);
  const nlohmann::json report = {{"kind", "segmenter average"},
                                 {"models", options.models},
                                 {"half", options.half},
                                 {"model", model}};
  const std::string report_path = (fs::path(options.out) / "report.json").string();
  std::ofstream file(report_path);
  if (!(file << report.dump(2) << "\n")) ThrowInFile(report_path, "cannot be written");
  spdlog::info("average of {} segmenters written to {}", options.models.size(), model);
}

}  // namespace moslam::weak
