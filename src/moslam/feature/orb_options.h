// Options of the ORB extractor (Rublee et al. 2011 "ORB: an efficient alternative to SIFT or SURF",
// as used by ORB-SLAM2, Mur-Artal & Tardós 2017) with the movable-object mask of Sun et al. 2019.
#pragma once

#include "moslam/util/yaml.h"

namespace moslam::feature {

struct OrbExtractorOptions {
  // Keypoints wanted per image, over all pyramid levels. ORB-SLAM2 key ORBextractor.nFeatures.
  int num_features = 1000;
  // Ratio between the sides of consecutive pyramid levels (> 1). ORBextractor.scaleFactor.
  double scale_factor = 1.2;
  // Number of pyramid levels (>= 1). ORBextractor.nLevels.
  int num_levels = 8;
  // FAST threshold, grey levels (0-255), tried first in every grid cell. ORBextractor.iniThFAST.
  int ini_th_fast = 20;
  // Lower FAST threshold, grey levels, used in a cell where ini_th_fast finds no corner
  // (0 < min_th_fast <= ini_th_fast). ORBextractor.minThFAST.
  int min_th_fast = 7;
  // Radius in level-0 pixels by which the movable-object mask is grown before keypoints on it are
  // dropped (>= 0); covers segmentation boundaries that are a little too tight.
  int mask_dilation_px = 0;
  // Side of the grid cells in which FAST runs, in pixels of each level (>= 10). Cells make the
  // detector adapt its threshold locally, so low-contrast regions still get candidates.
  int cell_size_px = 30;

  // Throws InputError naming the option (and its ORB-SLAM2 key) when a value is invalid.
  void Check() const;
};

// Reads the ORB-SLAM2 keys ORBextractor.{nFeatures, scaleFactor, nLevels, iniThFAST, minThFAST}
// (each optional: a missing key keeps the value in *options), then checks the result. Errors name
// the file and the key. The caller owns `file` and decides about unknown keys (RejectUnread).
void ReadOrbExtractorOptions(YamlFile& file, OrbExtractorOptions* options);

}  // namespace moslam::feature
