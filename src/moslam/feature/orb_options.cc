#include "moslam/feature/orb_options.h"

#include "moslam/util/error.h"

namespace moslam::feature {

void OrbExtractorOptions::Check() const {
  io::OrbExtractorOptions::Check();
  if (mask_dilation_px < 0 || mask_dilation_px > 1000) {
    ThrowInput("ORB option mask_dilation_px must be in [0, 1000] pixels, got {}", mask_dilation_px);
  }
  if (cell_size_px < 10 || cell_size_px > 1000) {
    ThrowInput("ORB option cell_size_px must be in [10, 1000] pixels, got {}", cell_size_px);
  }
}

}  // namespace moslam::feature
