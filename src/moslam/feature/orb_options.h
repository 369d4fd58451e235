// Options of the ORB extractor (Rublee et al. 2011 "ORB: an efficient alternative to SIFT or SURF",
// as used by ORB-SLAM2, Mur-Artal & Tardós 2017) with the movable-object mask of Sun et al. 2019.
#pragma once

#include "moslam/io/orbslam_settings.h"

namespace moslam::feature {

// The ORB-SLAM2 keys (num_features, scale_factor, num_levels, ini_th_fast, min_th_fast) are
// io::OrbExtractorOptions, read from settings files by io::LoadOrbSlamSettings; this struct adds
// what only the extractor needs. Assign a settings file's values with ApplySettings.
struct OrbExtractorOptions : io::OrbExtractorOptions {
  // Radius in level-0 pixels by which the movable-object mask is grown before keypoints on it are
  // dropped (>= 0); covers segmentation boundaries that are a little too tight.
  int mask_dilation_px = 0;
  // Side of the grid cells in which FAST runs, in pixels of each level (>= 10). Cells make the
  // detector adapt its threshold locally, so low-contrast regions still get candidates.
  int cell_size_px = 30;

  // Throws InputError naming the option (and its ORB-SLAM2 key) when a value is invalid.
  void Check() const;
  // Takes the ORB-SLAM2 values of a settings file, keeping the extractor-only options.
  void ApplySettings(const io::OrbExtractorOptions& settings) {
    static_cast<io::OrbExtractorOptions&>(*this) = settings;
  }
};

}  // namespace moslam::feature
