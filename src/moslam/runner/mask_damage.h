// A degraded-mask source for tests and ablations (issue 24): another source's masks (normally the
// generator's exact ones, synth-gt) with controlled damage, so that each mechanism that copes
// with imperfect masks can be measured without a network. The damage imitates how a weak
// network fails: it misses whole frames, loses the parts of bodies at the image's border (people
// entering or leaving), under-covers the extent (erosion) and leaves holes.
//
//   moslam run ... --mask-source synth-gt --mask-damage miss=0.2,border=40,erode=3,holes=0.2
//
// Every frame's damage is drawn from (seed, frame index) alone, so it is the same in every run
// and in every thread.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "moslam/runner/mask_source.h"

namespace moslam::runner {

struct MaskDamageOptions {
  double miss = 0.0;        // share of frames whose mask is dropped entirely, 0..1
  int border_px = 0;        // mask pixels within this distance of the image's border dropped
  int erode_px = 0;         // the mask eroded by this many pixels (elliptic element)
  double holes = 0.0;       // share of the mask's area cut away in round holes, 0..1
  int hole_radius_px = 12;  // radius of each hole
  uint64_t seed = 1;
  bool Any() const { return miss > 0.0 || border_px > 0 || erode_px > 0 || holes > 0.0; }
  void Check() const;  // InputError naming the key (as --mask-damage spells it)
};

// "miss=0.2,border=40,erode=3,holes=0.2,radius=12,seed=7" (any subset, any order). InputError
// naming the key for an unknown key or a bad value.
MaskDamageOptions ParseMaskDamage(const std::string& spec);

// The damaged mask of frame `frame_index` (CV_8UC1 0/255; empty stays empty).
cv::Mat DamageMask(const cv::Mat& mask, int frame_index, const MaskDamageOptions& options);

// `inner`'s masks, damaged (FrameMask::fraction recomputed).
std::unique_ptr<MaskSource> MakeDamagedMaskSource(std::unique_ptr<MaskSource> inner,
                                                  const MaskDamageOptions& options);

}  // namespace moslam::runner
