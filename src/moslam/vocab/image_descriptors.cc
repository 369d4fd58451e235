#include "moslam/vocab/image_descriptors.h"

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <mutex>
#include <thread>

#include <opencv2/imgcodecs.hpp>

#include "moslam/feature/orb_extractor.h"
#include "moslam/util/error.h"
#include "moslam/util/progress.h"
#include "moslam/util/text_file.h"

namespace moslam::vocab {

std::vector<std::string> ListImages(const std::string& dir) {
  RequireDirectory(dir, "image folder");
  std::vector<std::string> paths;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".ppm" ||
        ext == ".bmp") {
      paths.push_back(entry.path().string());
    }
  }
  if (paths.empty()) ThrowInFile(dir, "no images (.png, .jpg, .jpeg, .pgm, .ppm, .bmp) in folder");
  std::sort(paths.begin(), paths.end());
  return paths;
}

std::vector<cv::Mat> ExtractDescriptors(const std::vector<std::string>& paths,
                                        const feature::OrbExtractorOptions& options, int threads,
                                        const std::string& progress_label) {
  options.Check();
  if (threads < 1) ThrowInput("ExtractDescriptors: threads must be >= 1, got {}", threads);
  std::vector<cv::Mat> descriptors(paths.size());
  std::atomic<size_t> next{0};
  std::mutex mutex;  // guards progress, done and error
  Progress progress(progress_label, paths.size(), 2.0, "images");
  size_t done = 0;
  std::string error;
  auto worker = [&] {
    feature::OrbExtractor extractor(options);  // not thread-safe: one per thread
    for (size_t i = next++; i < paths.size(); i = next++) {
      const cv::Mat image = cv::imread(paths[i], cv::IMREAD_GRAYSCALE);
      if (image.empty() || image.cols < 64 || image.rows < 64) {
        std::lock_guard<std::mutex> lock(mutex);
        if (error.empty()) error = paths[i] + ": cannot be read as an image of at least 64x64";
        return;
      }
      cv::Mat d = extractor.Extract(image).descriptors;
      std::lock_guard<std::mutex> lock(mutex);
      descriptors[i] = std::move(d);
      progress.Update(++done);
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& thread : pool) thread.join();
  if (!error.empty()) throw InputError(error);
  progress.Finish();
  return descriptors;
}

}  // namespace moslam::vocab
