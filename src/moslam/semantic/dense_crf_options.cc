// DenseCrfOptions: validation and YAML loading.
#include <cmath>

#include "moslam/semantic/dense_crf.h"
#include "moslam/util/error.h"
#include "moslam/util/yaml.h"

namespace moslam::semantic {
namespace {

void RequirePositive(float value, const char* name) {
  if (!(value > 0.0f) || !std::isfinite(value)) {
    ThrowInput("CRF option {} must be a positive finite number, got {}", name, value);
  }
}

void RequireNonNegative(float value, const char* name) {
  if (!(value >= 0.0f) || !std::isfinite(value)) {
    ThrowInput("CRF option {} must be a non-negative finite number, got {}", name, value);
  }
}

}  // namespace

void DenseCrfOptions::Check() const {
  if (iterations < 0 || iterations > 1000) {
    ThrowInput("CRF option iterations must be in [0, 1000], got {}", iterations);
  }
  // Standard deviations below these make the lattice coordinates of large images overflow and
  // are meaningless anyway (a kernel narrower than a pixel or an intensity level).
  RequirePositive(smoothness_sxy, "smoothness_sxy");
  RequirePositive(appearance_sxy, "appearance_sxy");
  RequirePositive(appearance_srgb, "appearance_srgb");
  RequirePositive(depth_sxy, "depth_sxy");
  RequirePositive(depth_sd_m, "depth_sd_m");
  if (smoothness_sxy < 0.5f || appearance_sxy < 0.5f || depth_sxy < 0.5f) {
    ThrowInput("CRF options *_sxy must be at least 0.5 pixels");
  }
  if (appearance_srgb < 0.5f) ThrowInput("CRF option appearance_srgb must be at least 0.5");
  if (smoothness_filter != "auto" && smoothness_filter != "lattice" &&
      smoothness_filter != "separable") {
    ThrowInput("CRF option smoothness_filter must be auto, lattice or separable, got '{}'",
               smoothness_filter);
  }
  RequireNonNegative(smoothness_weight, "smoothness_weight");
  RequireNonNegative(appearance_weight, "appearance_weight");
  RequireNonNegative(depth_weight, "depth_weight");
  if (!(min_probability > 0.0f && min_probability < 1.0f)) {
    ThrowInput("CRF option min_probability must be in (0, 1), got {}", min_probability);
  }
  if (!compatibility.empty()) {
    const auto n = static_cast<size_t>(std::lround(std::sqrt(compatibility.size())));
    if (n * n != compatibility.size() || n < 2 || n > 32) {
      ThrowInput("CRF option compatibility must hold L x L numbers for 2 <= L <= 32, got {}",
                 compatibility.size());
    }
    for (double v : compatibility) {
      if (!std::isfinite(v)) ThrowInput("CRF option compatibility holds a non-finite value");
    }
  }
  if (num_threads < 1 || num_threads > 64) {
    ThrowInput("CRF option num_threads must be in [1, 64], got {}", num_threads);
  }
}

void ReadDenseCrfOptions(YamlFile& file, const std::string& prefix, DenseCrfOptions* options) {
  file.Read(prefix + "iterations", &options->iterations);
  file.Read(prefix + "smoothness", &options->smoothness);
  file.Read(prefix + "smoothness_sxy", &options->smoothness_sxy);
  file.Read(prefix + "smoothness_weight", &options->smoothness_weight);
  file.Read(prefix + "smoothness_filter", &options->smoothness_filter);
  file.Read(prefix + "appearance", &options->appearance);
  file.Read(prefix + "appearance_sxy", &options->appearance_sxy);
  file.Read(prefix + "appearance_srgb", &options->appearance_srgb);
  file.Read(prefix + "appearance_weight", &options->appearance_weight);
  file.Read(prefix + "depth", &options->depth);
  file.Read(prefix + "depth_sxy", &options->depth_sxy);
  file.Read(prefix + "depth_sd_m", &options->depth_sd_m);
  file.Read(prefix + "depth_weight", &options->depth_weight);
  file.Read(prefix + "min_probability", &options->min_probability);
  file.Read(prefix + "compatibility", &options->compatibility);
  file.Read(prefix + "num_threads", &options->num_threads);
  try {
    options->Check();
  } catch (const InputError& e) {
    ThrowInFile(file.path(), e.what());
  }
}

DenseCrfOptions LoadDenseCrfOptions(const std::string& path) {
  YamlFile file(path);
  DenseCrfOptions options;
  ReadDenseCrfOptions(file, "crf.", &options);
  file.RejectUnread();
  return options;
}

}  // namespace moslam::semantic
