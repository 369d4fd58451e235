#include "moslam/feature/orb_options.h"

#include "moslam/util/error.h"

namespace moslam::feature {

void OrbExtractorOptions::Check() const {
  if (num_features < 1) {
    ThrowInput("ORB option num_features (ORBextractor.nFeatures) must be >= 1, got {}",
               num_features);
  }
  // The upper bound keeps the level sizes meaningful; ORB-SLAM2 uses 1.2.
  if (!(scale_factor > 1.0 && scale_factor <= 4.0)) {
    ThrowInput("ORB option scale_factor (ORBextractor.scaleFactor) must be in (1, 4], got {}",
               scale_factor);
  }
  if (num_levels < 1 || num_levels > 32) {
    ThrowInput("ORB option num_levels (ORBextractor.nLevels) must be in [1, 32], got {}",
               num_levels);
  }
  if (ini_th_fast < 1 || ini_th_fast > 254) {
    ThrowInput("ORB option ini_th_fast (ORBextractor.iniThFAST) must be in [1, 254], got {}",
               ini_th_fast);
  }
  if (min_th_fast < 1 || min_th_fast > ini_th_fast) {
    ThrowInput(
        "ORB option min_th_fast (ORBextractor.minThFAST) must be in [1, iniThFAST = {}], got {}",
        ini_th_fast, min_th_fast);
  }
  if (mask_dilation_px < 0 || mask_dilation_px > 1000) {
    ThrowInput("ORB option mask_dilation_px must be in [0, 1000] pixels, got {}", mask_dilation_px);
  }
  if (cell_size_px < 10 || cell_size_px > 1000) {
    ThrowInput("ORB option cell_size_px must be in [10, 1000] pixels, got {}", cell_size_px);
  }
}

void ReadOrbExtractorOptions(YamlFile& file, OrbExtractorOptions* options) {
  file.Read("ORBextractor.nFeatures", &options->num_features);
  file.Read("ORBextractor.scaleFactor", &options->scale_factor);
  file.Read("ORBextractor.nLevels", &options->num_levels);
  file.Read("ORBextractor.iniThFAST", &options->ini_th_fast);
  file.Read("ORBextractor.minThFAST", &options->min_th_fast);
  try {
    options->Check();
  } catch (const InputError& e) {
    ThrowInFile(file.path(), e.what());
  }
}

}  // namespace moslam::feature
