#include "moslam/io/tum_rgbd.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <tuple>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "moslam/io/index_file.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/util/text_file.h"

namespace moslam::io {
namespace {

namespace fs = std::filesystem;

std::string ParentFolder(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

std::vector<FrameEntry> ReadAssociationsFile(const std::string& path, const std::string& folder) {
  std::vector<FrameEntry> frames;
  std::optional<double> previous;
  for (const TextLine& line : ReadDataLines(path)) {
    const auto fields =
        internal::SplitExactly(path, line, 4, false, "'t_rgb rgb_path t_depth depth_path'");
    const double t_rgb = internal::ParseSeconds(path, line, fields[0]);
    internal::ParseSeconds(path, line, fields[2]);  // validated, but frames use the RGB stamp
    internal::RequireIncreasing(path, line, previous, t_rgb);
    previous = t_rgb;
    FrameEntry frame;
    frame.index = static_cast<int>(frames.size());
    frame.timestamp = t_rgb;
    frame.image_left = internal::ResolvePath(folder, fields[1]);
    frame.depth = internal::ResolvePath(folder, fields[3]);
    internal::RequireListedFile(path, line.number, frame.image_left);
    internal::RequireListedFile(path, line.number, frame.depth);
    frames.push_back(std::move(frame));
  }
  if (frames.empty()) ThrowInFile(path, "lists no frames");
  return frames;
}

std::vector<double> Stamps(const std::vector<StampedFile>& files) {
  std::vector<double> stamps;
  stamps.reserve(files.size());
  for (const StampedFile& f : files) stamps.push_back(f.timestamp);
  return stamps;
}

std::vector<FrameEntry> AssociateLists(const std::string& folder, const TumRgbdOptions& options) {
  const std::string rgb_path = (fs::path(folder) / "rgb.txt").string();
  const std::string depth_path = (fs::path(folder) / "depth.txt").string();
  const std::vector<StampedFile> rgb = ReadTumFileList(rgb_path);
  const std::vector<StampedFile> depth = ReadTumFileList(depth_path);
  const auto pairs =
      AssociateTimestamps(Stamps(rgb), Stamps(depth), options.offset, options.max_difference);
  if (pairs.empty()) {
    ThrowInFile(folder, fmt::format("no RGB image has a depth image within {} s (offset {} s): "
                                    "check rgb.txt and depth.txt, or raise max_difference",
                                    options.max_difference, options.offset));
  }
  if (pairs.size() < rgb.size()) {
    spdlog::info("{}: {} of {} RGB images have a depth image within {} s", folder, pairs.size(),
                 rgb.size(), options.max_difference);
  }
  std::vector<FrameEntry> frames;
  frames.reserve(pairs.size());
  for (const auto& [i, j] : pairs) {
    FrameEntry frame;
    frame.index = static_cast<int>(frames.size());
    frame.timestamp = rgb[i].timestamp;
    frame.image_left = rgb[i].path;
    frame.depth = depth[j].path;
    frames.push_back(std::move(frame));
  }
  return frames;
}

}  // namespace

void TumRgbdOptions::Check() const {
  if (!std::isfinite(max_difference) || !(max_difference > 0.0)) {
    ThrowInput("TUM association max_difference must be a positive number of seconds, got {}",
               max_difference);
  }
  if (!std::isfinite(offset)) {
    ThrowInput("TUM association offset must be a finite number of seconds, got {}", offset);
  }
}

std::vector<StampedFile> ReadTumFileList(const std::string& path) {
  const std::string folder = ParentFolder(path);
  std::vector<StampedFile> files;
  std::optional<double> previous;
  for (const TextLine& line : ReadDataLines(path)) {
    const auto fields = internal::SplitExactly(path, line, 2, false, "'timestamp filename'");
    StampedFile file;
    file.line = line.number;
    file.timestamp = internal::ParseSeconds(path, line, fields[0]);
    internal::RequireIncreasing(path, line, previous, file.timestamp);
    previous = file.timestamp;
    file.path = internal::ResolvePath(folder, fields[1]);
    internal::RequireListedFile(path, line.number, file.path);
    files.push_back(std::move(file));
  }
  if (files.empty()) ThrowInFile(path, "lists no images");
  return files;
}

std::vector<std::pair<size_t, size_t>> AssociateTimestamps(const std::vector<double>& first,
                                                           const std::vector<double>& second,
                                                           double offset, double max_difference) {
  for (double t : first) MOSLAM_CHECK(std::isfinite(t)) << "stamp " << t;
  for (double t : second) MOSLAM_CHECK(std::isfinite(t)) << "stamp " << t;
  MOSLAM_CHECK(std::isfinite(offset) && max_difference > 0.0) << offset << " " << max_difference;
  // The candidates of associate.py, found with a sorted index of `second` instead of its
  // all-pairs loop; the search window is widened and the exact test applied afterwards so that
  // rounding in the window bounds cannot drop a candidate.
  std::vector<size_t> order(second.size());
  for (size_t j = 0; j < order.size(); ++j) order[j] = j;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return second[a] < second[b]; });
  std::vector<double> sorted;
  sorted.reserve(order.size());
  for (size_t j : order) sorted.push_back(second[j]);

  struct Candidate {
    double difference;
    size_t i, j;
  };
  std::vector<Candidate> candidates;
  for (size_t i = 0; i < first.size(); ++i) {
    const double target = first[i] - offset;
    const auto lo = std::lower_bound(sorted.begin(), sorted.end(), target - 2.0 * max_difference);
    const auto hi = std::upper_bound(sorted.begin(), sorted.end(), target + 2.0 * max_difference);
    for (auto it = lo; it != hi; ++it) {
      const size_t j = order[static_cast<size_t>(it - sorted.begin())];
      const double difference = std::abs(first[i] - (second[j] + offset));
      if (difference < max_difference) candidates.push_back({difference, i, j});
    }
  }
  // Python sorts the tuples (difference, a, b): ties go to the earlier first stamp, then second.
  std::sort(candidates.begin(), candidates.end(), [&](const Candidate& a, const Candidate& b) {
    return std::make_tuple(a.difference, first[a.i], second[a.j], a.i, a.j) <
           std::make_tuple(b.difference, first[b.i], second[b.j], b.i, b.j);
  });
  std::vector<bool> first_used(first.size(), false), second_used(second.size(), false);
  std::vector<std::pair<size_t, size_t>> matches;
  for (const Candidate& c : candidates) {
    if (first_used[c.i] || second_used[c.j]) continue;
    first_used[c.i] = second_used[c.j] = true;
    matches.emplace_back(c.i, c.j);
  }
  std::sort(matches.begin(), matches.end(), [&](const auto& a, const auto& b) {
    return std::make_tuple(first[a.first], second[a.second]) <
           std::make_tuple(first[b.first], second[b.second]);
  });
  return matches;
}

Sequence ReadTumRgbd(const std::string& folder, const TumRgbdOptions& options) {
  options.Check();
  RequireDirectory(folder, "TUM RGB-D sequence folder");
  Sequence sequence;
  sequence.name = internal::FolderName(folder);
  sequence.root = folder;
  sequence.sensor = SensorType::kRgbD;
  sequence.frames = options.associations_path.empty()
                        ? AssociateLists(folder, options)
                        : ReadAssociationsFile(options.associations_path, folder);
  sequence.ground_truth_path = internal::ExistingFile(folder, "groundtruth.txt");
  return sequence;
}

}  // namespace moslam::io
