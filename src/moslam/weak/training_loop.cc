#include "moslam/weak/training_loop.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/net/model_file.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/util/progress.h"

namespace moslam::weak::internal {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

torch::Device TrainingDevice() {
  if (torch::cuda::is_available()) {
    spdlog::info("training on CUDA device 0 ({} visible)", torch::cuda::device_count());
    return torch::Device(torch::kCUDA, 0);
  }
  spdlog::info("training on the CPU ({} threads)", at::get_num_threads());
  return torch::Device(torch::kCPU);
}

ImageList LoadTrainingList(const CommonTrainOptions& options) {
  ImageList list = options.data.Load();
  if (options.max_images > 0 && static_cast<int>(list.entries.size()) > options.max_images) {
    list.entries.resize(options.max_images);
  }
  return list;
}

void WriteReport(const CommonTrainOptions& options, const std::string& kind,
                 const TrainSummary& summary, const net::NetConfig& config, size_t images,
                 const nlohmann::json& extra) {
  nlohmann::json report = {{"kind", kind},
                           {"model", summary.model},
                           {"config", net::ToJson(config)},
                           {"images", images},
                           {"epochs", summary.epochs},
                           {"final_loss", summary.final_loss},
                           {"seconds_this_run", summary.seconds}};
  report.update(extra);
  std::ofstream(fs::path(options.out) / "report.json") << report.dump(2) << "\n";
  spdlog::info("{} written to {} ({:.0f} s)", kind, summary.model, summary.seconds);
}

void MakeFolder(const std::string& folder) {
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) throw InputError(fmt::format("cannot create folder {}: {}", folder, error.message()));
}

nlohmann::json ToJson(const std::vector<EpochRecord>& history) {
  nlohmann::json out = nlohmann::json::array();
  for (const EpochRecord& r : history) {
    nlohmann::json j = {{"epoch", r.epoch},
                        {"loss", r.loss},
                        {"images_per_s", r.images_per_s},
                        {"seconds", r.seconds},
                        {"parts", r.parts}};
    if (std::isfinite(r.accuracy)) j["accuracy"] = r.accuracy;
    out.push_back(j);
  }
  return out;
}

std::vector<EpochRecord> HistoryFromJson(const nlohmann::json& json) {
  std::vector<EpochRecord> history;
  for (const auto& j : json) {
    EpochRecord r;
    r.epoch = j.at("epoch").get<int>();
    r.loss = j.at("loss").get<double>();
    r.accuracy = j.contains("accuracy") ? j.at("accuracy").get<double>()
                                        : std::numeric_limits<double>::quiet_NaN();
    r.parts = j.at("parts").get<std::map<std::string, double>>();
    r.images_per_s = j.at("images_per_s").get<double>();
    r.seconds = j.at("seconds").get<double>();
    history.push_back(r);
  }
  return history;
}

namespace {

// A polyline of `values` (one per epoch) in the plot rectangle, scaled to [lo, hi].
void DrawSeries(cv::Mat& image, const cv::Rect& area, const std::vector<double>& values, double lo,
                double hi, int epochs, const cv::Scalar& colour) {
  std::vector<cv::Point> points;
  for (size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) continue;
    const double fx = epochs > 1 ? static_cast<double>(i) / (epochs - 1) : 0.5;
    const double fy = hi > lo ? (values[i] - lo) / (hi - lo) : 0.5;
    points.emplace_back(area.x + static_cast<int>(fx * area.width),
                        area.y + area.height - static_cast<int>(fy * area.height));
  }
  if (points.size() >= 2) cv::polylines(image, points, false, colour, 2, cv::LINE_AA);
  for (const cv::Point& p : points) cv::circle(image, p, 3, colour, cv::FILLED, cv::LINE_AA);
}

void PutText(cv::Mat& image, const std::string& text, cv::Point at, const cv::Scalar& colour,
             double size = 0.5) {
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, size, colour, 1, cv::LINE_AA);
}

}  // namespace

cv::Mat RenderTrainingCurve(const std::vector<EpochRecord>& history, const std::string& title) {
  cv::Mat image(480, 800, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Rect area(70, 50, 640, 360);
  cv::rectangle(image, area, cv::Scalar(180, 180, 180), 1);
  PutText(image, title, {70, 30}, cv::Scalar(0, 0, 0), 0.6);
  const int epochs = static_cast<int>(history.size());
  if (epochs == 0) return image;
  // Loss and its parts share the left axis, from 0 to the largest value.
  std::map<std::string, std::vector<double>> series;
  std::vector<double> accuracy;
  for (const EpochRecord& r : history) {
    series["loss"].push_back(r.loss);
    for (const auto& [name, value] : r.parts) series[name].push_back(value);
    accuracy.push_back(r.accuracy);
  }
  double hi = 0.0;
  for (const auto& [name, values] : series) {
    for (double v : values) hi = std::max(hi, std::isfinite(v) ? v : 0.0);
  }
  if (hi <= 0.0) hi = 1.0;
  const std::vector<cv::Scalar> palette = {{200, 60, 20},  {30, 140, 30}, {150, 40, 150},
                                           {20, 120, 200}, {90, 90, 90},  {0, 180, 180}};
  int legend_y = 465, legend_x = 70, colour_index = 0;
  for (const auto& [name, values] : series) {
    const cv::Scalar colour = palette[colour_index++ % palette.size()];
    DrawSeries(image, area, values, 0.0, hi, epochs, colour);
    PutText(image, name, {legend_x, legend_y}, colour);
    legend_x += 20 + 10 * static_cast<int>(name.size());
  }
  if (std::any_of(accuracy.begin(), accuracy.end(), [](double a) { return std::isfinite(a); })) {
    DrawSeries(image, area, accuracy, 0.0, 1.0, epochs, cv::Scalar(0, 0, 220));
    PutText(image, "accuracy (right axis, 0-1)", {legend_x, legend_y}, cv::Scalar(0, 0, 220));
    PutText(image, "1.0", {area.br().x + 8, area.y + 5}, cv::Scalar(0, 0, 220));
    PutText(image, "0", {area.br().x + 8, area.br().y}, cv::Scalar(0, 0, 220));
  }
  PutText(image, fmt::format("{:.3g}", hi), {10, area.y + 5}, cv::Scalar(0, 0, 0));
  PutText(image, "0", {50, area.br().y}, cv::Scalar(0, 0, 0));
  PutText(image, "epoch 1", {area.x, area.br().y + 20}, cv::Scalar(0, 0, 0));
  PutText(image, fmt::format("epoch {}", epochs), {area.br().x - 60, area.br().y + 20},
          cv::Scalar(0, 0, 0));
  return image;
}

std::unique_ptr<torch::optim::Adam> MakeOptimizer(torch::nn::Module& backbone,
                                                  torch::nn::Module& whole,
                                                  const CommonTrainOptions& options) {
  std::vector<torch::Tensor> backbone_params, head_params;
  const auto in_backbone = backbone.parameters();
  auto is_backbone = [&](const torch::Tensor& t) {
    return std::any_of(in_backbone.begin(), in_backbone.end(),
                       [&](const torch::Tensor& b) { return b.is_same(t); });
  };
  for (const torch::Tensor& p : whole.parameters()) {
    if (!p.requires_grad()) continue;
    (is_backbone(p) ? backbone_params : head_params).push_back(p);
  }
  std::vector<torch::optim::OptimizerParamGroup> groups;
  auto group = [&](std::vector<torch::Tensor> params, double lr) {
    auto adam = std::make_unique<torch::optim::AdamOptions>(lr);
    adam->weight_decay(options.weight_decay);
    groups.emplace_back(std::move(params), std::move(adam));
  };
  if (!backbone_params.empty()) {
    group(backbone_params, options.learning_rate * options.backbone_lr_factor);
  }
  group(head_params, options.learning_rate);
  return std::make_unique<torch::optim::Adam>(std::move(groups),
                                              torch::optim::AdamOptions(options.learning_rate));
}

void SetPolyLearningRate(torch::optim::Adam& optimizer, const std::vector<double>& initial,
                         int64_t step, int64_t total_steps) {
  const double progress =
      total_steps > 0 ? std::min(1.0, static_cast<double>(step) / total_steps) : 0.0;
  const double factor = std::pow(1.0 - progress, 0.9);
  auto& groups = optimizer.param_groups();
  for (size_t g = 0; g < groups.size() && g < initial.size(); ++g) {
    static_cast<torch::optim::AdamOptions&>(groups[g].options()).lr(initial[g] * factor);
  }
}

namespace {

std::vector<double> InitialRates(torch::optim::Adam& optimizer) {
  std::vector<double> rates;
  for (auto& group : optimizer.param_groups()) {
    rates.push_back(static_cast<torch::optim::AdamOptions&>(group.options()).lr());
  }
  return rates;
}

// Progress of one epoch: on a terminal a bar redrawn in place, otherwise a line every 10 s.
class EpochProgress {
 public:
  EpochProgress(std::string label, size_t total)
      : label_(std::move(label)), total_(total), terminal_(isatty(fileno(stderr)) != 0) {}

  void Update(size_t done, double loss, double accuracy) {
    const auto now = Clock::now();
    const double since = std::chrono::duration<double>(now - last_).count();
    if (done < total_ && since < (terminal_ ? 0.2 : 10.0)) return;
    last_ = now;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    std::string line = FormatProgress(label_, done, total_, elapsed, terminal_, "img");
    line += fmt::format("  loss {:.4f}", loss);
    if (std::isfinite(accuracy)) line += fmt::format("  acc {:.3f}", accuracy);
    if (terminal_ && done < total_) {
      std::fprintf(stderr, "\r%s\033[K", line.c_str());
      std::fflush(stderr);
    } else {
      if (terminal_) std::fprintf(stderr, "\r\033[K");
      spdlog::info("{}", line);
    }
  }

 private:
  std::string label_;
  size_t total_;
  bool terminal_;
  Clock::time_point start_ = Clock::now();
  Clock::time_point last_ = Clock::now();
};

EpochRecord RunEpoch(const CommonTrainOptions& options, const LoopSpec& spec, int epoch,
                     int64_t* step, int64_t total_steps, const std::vector<double>& rates) {
  std::vector<int> order(spec.num_images);
  std::iota(order.begin(), order.end(), 0);
  std::mt19937_64 rng(options.seed * 1000003ULL + static_cast<uint64_t>(epoch));
  std::shuffle(order.begin(), order.end(), rng);
  EpochProgress progress(fmt::format("{} epoch {}/{}", spec.name, epoch, options.epochs),
                         order.size());
  const auto start = Clock::now();
  double loss_sum = 0.0, correct = 0.0, count = 0.0;
  std::map<std::string, double> parts;
  int images = 0, batches = 0;
  for (size_t first = 0; first < order.size(); first += options.batch_size) {
    const size_t last = std::min(order.size(), first + options.batch_size);
    std::vector<int> batch(order.begin() + first, order.begin() + last);
    SetPolyLearningRate(*spec.optimizer, rates, (*step)++, total_steps);
    const StepStats stats = spec.step(batch, rng);
    loss_sum += stats.loss;
    for (const auto& [name, value] : stats.parts) parts[name] += value;
    correct += stats.correct;
    count += stats.count;
    images += stats.images;
    ++batches;
    progress.Update(last, loss_sum / batches,
                    count > 0 ? correct / count : std::numeric_limits<double>::quiet_NaN());
  }
  EpochRecord record;
  record.epoch = epoch;
  record.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  record.loss = batches > 0 ? loss_sum / batches : 0.0;
  for (auto& [name, value] : parts) record.parts[name] = value / std::max(1, batches);
  record.accuracy = count > 0 ? correct / count : std::numeric_limits<double>::quiet_NaN();
  record.images_per_s = record.seconds > 0 ? images / record.seconds : 0.0;
  return record;
}

}  // namespace

TrainSummary RunTrainingLoop(const CommonTrainOptions& options, const LoopSpec& spec) {
  MOSLAM_CHECK(spec.net && spec.config && spec.optimizer && spec.step && spec.save_model);
  if (spec.num_images <= 0) throw InputError(spec.name + ": no training images");
  MakeFolder(options.out);
  const std::string checkpoint = (fs::path(options.out) / "checkpoint.mnet").string();
  const std::vector<double> rates = InitialRates(*spec.optimizer);
  std::vector<EpochRecord> history;
  int first_epoch = 1;
  if (options.resume && fs::exists(checkpoint)) {
    const nlohmann::json state = net::LoadCheckpoint(checkpoint, *spec.net, *spec.optimizer);
    history = HistoryFromJson(state.at("history"));
    first_epoch = state.at("epoch").get<int>() + 1;
    spdlog::info("{}: resuming after epoch {} from {}", spec.name, first_epoch - 1, checkpoint);
  } else if (options.resume) {
    spdlog::warn("{}: --resume given but {} does not exist; starting afresh", spec.name,
                 checkpoint);
  }
  const int64_t batches_per_epoch = (spec.num_images + options.batch_size - 1) / options.batch_size;
  const int64_t total_steps = batches_per_epoch * options.epochs;
  int64_t step = batches_per_epoch * (first_epoch - 1);
  const auto start = Clock::now();
  spec.net->train();
  for (int epoch = first_epoch; epoch <= options.epochs; ++epoch) {
    history.push_back(RunEpoch(options, spec, epoch, &step, total_steps, rates));
    const EpochRecord& r = history.back();
    spdlog::info("{} epoch {}/{}: loss {:.4f}{}, {:.1f} images/s, {:.0f} s", spec.name, epoch,
                 options.epochs, r.loss,
                 std::isfinite(r.accuracy) ? fmt::format(", accuracy {:.3f}", r.accuracy) : "",
                 r.images_per_s, r.seconds);
    const nlohmann::json state = {{"epoch", epoch}, {"history", ToJson(history)}};
    net::SaveCheckpoint(checkpoint, *spec.net, *spec.config, *spec.optimizer, state);
    cv::imwrite((fs::path(options.out) / "curve.png").string(),
                RenderTrainingCurve(history, spec.name));
    std::ofstream(fs::path(options.out) / "history.json") << ToJson(history).dump(2) << "\n";
  }
  spec.net->eval();
  TrainSummary summary;
  summary.model = (fs::path(options.out) / "model.mnet").string();
  spec.save_model(summary.model);
  summary.epochs = options.epochs;
  summary.final_loss = history.empty() ? 0.0 : history.back().loss;
  summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return summary;
}

torch::Tensor MeanOverViews(const cv::Mat& image, const std::vector<double>& scales, bool flip,
                            torch::Device device,
                            const std::function<torch::Tensor(const torch::Tensor&)>& map,
                            const std::function<torch::Tensor(const torch::Tensor&)>& activation) {
  MOSLAM_CHECK(!scales.empty());
  torch::NoGradGuard no_grad;
  torch::Tensor sum;
  int views = 0;
  for (double scale : scales) {
    cv::Mat scaled = image;
    if (scale != 1.0) {
      const cv::Size size(
          std::max(net::kMinInputSide, static_cast<int>(std::lround(image.cols * scale))),
          std::max(net::kMinInputSide, static_cast<int>(std::lround(image.rows * scale))));
      cv::resize(image, scaled, size, 0, 0, scale < 1.0 ? cv::INTER_AREA : cv::INTER_LINEAR);
    }
    const torch::Tensor input = ToInputTensor(scaled).unsqueeze(0).to(device);
    for (int mirrored = 0; mirrored <= (flip ? 1 : 0); ++mirrored) {
      torch::Tensor out = map(mirrored ? input.flip({3}) : input);
      if (mirrored) out = out.flip({3});
      const torch::Tensor view = activation(net::UpsampleBilinear(out, image.rows, image.cols));
      sum = views == 0 ? view : sum + view;
      ++views;
    }
  }
  return sum / views;
}

}  // namespace moslam::weak::internal
