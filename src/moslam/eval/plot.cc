#include "moslam/eval/plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>

#include "moslam/eval/plot_figure.h"
#include "moslam/eval/plot_layout.h"
#include "moslam/eval/plot_scale.h"
#include "moslam/util/atomic_file.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"

namespace moslam::eval {
namespace {

using internal::Figure;

enum class Format { kPng, kSvg };

Format FormatOf(const std::string& path) {
  const std::string lower = ToLower(path);
  if (EndsWith(lower, ".png")) return Format::kPng;
  if (EndsWith(lower, ".svg")) return Format::kSvg;
  ThrowInFile(path, "unknown plot format: the file name must end in .png or .svg");
}

void Validate(const TrajectoryPlotData& data, const std::string& path) {
  const size_t n = data.times.size();
  if (n == 0 && data.reference.empty() && data.estimate.empty()) {
    ThrowInFile(path, "cannot plot an empty trajectory (no poses)");
  }
  if (data.reference.size() != n || data.estimate.size() != n) {
    ThrowInFile(path, fmt::format("cannot plot: inconsistent lengths ({} times, {} reference and "
                                  "{} estimate positions)",
                                  n, data.reference.size(), data.estimate.size()));
  }
  if (n == 0) ThrowInFile(path, "cannot plot an empty trajectory (no poses)");
  if (data.errors.size() > n) {
    ThrowInFile(path, fmt::format("cannot plot: {} errors for {} poses (at most one per pose)",
                                  data.errors.size(), n));
  }
}

// Whole or not at all (util/atomic_file.h): a plot cut short by a full disk is never left behind.
void WriteBytes(const std::string& path, const char* bytes, size_t size) {
  WriteFileAtomically(path, std::string_view(bytes, size), "plot");
}

}  // namespace

void WriteTrajectoryPlot(const TrajectoryPlotData& data, const std::string& path) {
  const Format format = FormatOf(path);
  Validate(data, path);
  const Figure figure = internal::LayoutTrajectoryPlot(data);
  if (format == Format::kSvg) {
    const std::string svg = internal::RenderSvg(figure);
    WriteBytes(path, svg.data(), svg.size());
    return;
  }
  std::vector<std::uint8_t> png;
  if (!cv::imencode(".png", internal::RenderRaster(figure), png)) {
    ThrowInFile(path, "PNG encoding failed");
  }
  WriteBytes(path, reinterpret_cast<const char*>(png.data()), png.size());
}

}  // namespace moslam::eval
