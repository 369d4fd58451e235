// `moslam vocab`: bag-of-words vocabularies (docs/VOCABULARY.md).
//
//   moslam vocab train --images DIR [DIR ...] --out FILE [--k 10] [--levels 6]
//                      [--max-features 1000] [--every 1] [--threads 1] [--seed 1]
//   moslam vocab info FILE
//   moslam vocab convert IN OUT      (e.g. ORB-SLAM2's ORBvoc.txt -> binary, ~100x faster to load)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "commands.h"
#include "moslam/util/error.h"
#include "moslam/util/progress.h"
#include "moslam/vocab/image_descriptors.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::app {
namespace {

struct VocabTrainArgs {
  std::vector<std::string> image_dirs;
  std::string out;
  vocab::VocabularyTrainOptions options;
  int max_features = 1000;
  int every = 1;
};

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void RunTrain(const VocabTrainArgs& args) {
  args.options.Check();
  if (args.every < 1) ThrowInput("vocab train: --every must be >= 1, got {}", args.every);
  std::vector<std::string> paths;
  for (const std::string& dir : args.image_dirs) {
    const std::vector<std::string> listed = vocab::ListImages(dir);
    for (size_t i = 0; i < listed.size(); i += static_cast<size_t>(args.every)) {
      paths.push_back(listed[i]);
    }
  }
  spdlog::info("vocab train: {} images from {} folder(s)", paths.size(), args.image_dirs.size());
  feature::OrbExtractorOptions orb;  // ORB-SLAM2 defaults: 1.2, 8 levels, FAST 20 / 7
  orb.num_features = args.max_features;
  auto start = std::chrono::steady_clock::now();
  const std::vector<cv::Mat> descriptors =
      vocab::ExtractDescriptors(paths, orb, args.options.num_threads);
  size_t total = 0;
  for (const cv::Mat& d : descriptors) total += static_cast<size_t>(d.rows);
  spdlog::info("extracted {} descriptors ({:.0f} per image) in {:.1f} s", total,
               static_cast<double>(total) / paths.size(), SecondsSince(start));

  start = std::chrono::steady_clock::now();
  vocab::Vocabulary voc;
  {
    Progress progress("vocab clustering", 100, 5.0, "%");
    voc = vocab::Vocabulary::Train(descriptors, args.options, [&](double fraction) {
      progress.Update(static_cast<size_t>(fraction * 100.0));
    });
  }
  const double train_s = SecondsSince(start);
  spdlog::info("trained k = {}, levels = {}: {} words, {} nodes in {:.1f} s", voc.k(), voc.levels(),
               voc.size(), voc.num_nodes(), train_s);
  voc.Save(args.out);
  spdlog::info("wrote {} ({:.1f} MB)", args.out,
               static_cast<double>(std::filesystem::file_size(args.out)) / 1e6);
}

void RunInfo(const std::string& path) {
  const auto start = std::chrono::steady_clock::now();
  const vocab::Vocabulary voc = vocab::Vocabulary::Load(path);
  const double load_ms = 1000.0 * SecondsSince(start);
  std::vector<double> weights(voc.size());
  for (vocab::WordId w = 0; w < voc.size(); ++w) weights[w] = voc.Weight(w);
  std::sort(weights.begin(), weights.end());
  fmt::print("file       {} ({:.1f} MB)\n", path,
             static_cast<double>(std::filesystem::file_size(path)) / 1e6);
  fmt::print("tree       k = {}, levels = {}, {} nodes\n", voc.k(), voc.levels(), voc.num_nodes());
  fmt::print("words      {} (at most {:.0f})\n", voc.size(), std::pow(voc.k(), voc.levels()));
  fmt::print("IDF        min {:.3f}  median {:.3f}  max {:.3f}\n", weights.front(),
             weights[weights.size() / 2], weights.back());
  fmt::print("load time  {:.1f} ms\n", load_ms);
}

void RunConvert(const std::string& in, const std::string& out) {
  auto start = std::chrono::steady_clock::now();
  const vocab::Vocabulary voc = vocab::Vocabulary::Load(in);
  spdlog::info("loaded {} ({} words) in {:.2f} s", in, voc.size(), SecondsSince(start));
  voc.Save(out);
  spdlog::info("wrote {} ({:.1f} MB)", out,
               static_cast<double>(std::filesystem::file_size(out)) / 1e6);
}

}  // namespace

void AddVocabCommand(CLI::App& app) {
  CLI::App* command = app.add_subcommand(
      "vocab", "Bag-of-words vocabularies: train one from images, or describe one");
  command->require_subcommand(1);

  auto train = std::make_shared<VocabTrainArgs>();
  CLI::App* train_cmd = command->add_subcommand(
      "train", "Train a vocabulary (hierarchical k-medians of ORB descriptors, IDF weights)");
  train_cmd->add_option("--images", train->image_dirs, "Folders of training images (read as grey)")
      ->required()
      ->expected(1, -1);
  train_cmd->add_option("--out", train->out, "Vocabulary file to write (binary .mvoc)")->required();
  train_cmd->add_option("--k", train->options.k, "Children per node")->capture_default_str();
  train_cmd->add_option("--levels", train->options.levels, "Depth of the tree")
      ->capture_default_str();
  train_cmd->add_option("--max-features", train->max_features, "ORB features per image")
      ->capture_default_str();
  train_cmd->add_option("--every", train->every, "Use every N-th image of each folder")
      ->capture_default_str();
  train_cmd
      ->add_option("--max-iterations", train->options.max_iterations,
                   "k-medians iterations per node")
      ->capture_default_str();
  train_cmd
      ->add_option("--threads", train->options.num_threads,
                   "Threads for extraction and clustering (the result does not depend on it)")
      ->capture_default_str();
  train_cmd->add_option("--seed", train->options.seed, "Seed of the k-means++ seeding")
      ->capture_default_str();
  train_cmd->callback([train] { RunTrain(*train); });

  auto info_path = std::make_shared<std::string>();
  CLI::App* info_cmd = command->add_subcommand(
      "info", "Load a vocabulary (binary or DBoW2 text) and print its shape and load time");
  info_cmd->add_option("file", *info_path, "Vocabulary file")
      ->required()
      ->check(ExistingFileOf("vocabulary file"));
  info_cmd->callback([info_path] { RunInfo(*info_path); });

  auto convert_paths = std::make_shared<std::pair<std::string, std::string>>();
  CLI::App* convert_cmd = command->add_subcommand(
      "convert",
      "Convert a vocabulary (e.g. ORB-SLAM2's DBoW2 text ORBvoc.txt) to the binary format");
  convert_cmd->add_option("in", convert_paths->first, "Vocabulary file (binary or DBoW2 text)")
      ->required()
      ->check(ExistingFileOf("vocabulary file"));
  convert_cmd->add_option("out", convert_paths->second, "Binary vocabulary to write")->required();
  convert_cmd->callback(
      [convert_paths] { RunConvert(convert_paths->first, convert_paths->second); });
}

}  // namespace moslam::app
