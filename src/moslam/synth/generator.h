// `moslam synth`: renders a preset into a TUM RGB-D (or KITTI stereo) folder with exact ground
// truth, or independent training frames. See docs/SYNTH.md for the layout.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/synth/presets.h"
#include "moslam/synth/renderer.h"
#include "moslam/synth/sensor.h"

namespace moslam::synth {

struct GeneratorOptions {
  std::string preset;         // a name of Presets()
  uint64_t seed = 1;          // scene, people, camera path, procedural textures and noise
  std::string out;            // output folder (created; existing files are overwritten)
  int frames = 0;             // 0: the preset's default (like the TUM sequence it mimics)
  std::string textures_dir;   // photographs to add to the procedural textures; empty: none
  bool motion_blur = false;   // average 4 renders over a 1/60 s exposure (colour only)
  int width = 0, height = 0;  // 0: the preset's size (640x480 indoor, 1226x370 street)
  int texture_size = 512;     // procedural texture size (power of two)
  // Procedural textures of every kind (wall, floor, clothing, ...), 1..64. The presets' look is
  // that of the default 4; a larger set is a superset (its first 4 of a kind are the default's)
  // that gives training frames more appearances: a network trained on one seed's 4 floors and 4
  // shirts learns those textures, not people (docs/WEAK.md, "Texture variety").
  int textures_per_kind = 4;
  int png_compression = 1;   // 0-9: zlib level of every PNG (1: fast, ~1.5x larger than 9)
  bool sensor_noise = true;  // false: exact depth and colour (for ground-truth tests)
  bool progress = true;      // log progress lines
  // Also write depth_gt/<stamp>.png: the exact depth (no noise, no holes; factor 5000) for
  // ground-truth checks (synth/check.h). RGB-D presets only.
  bool write_exact_depth = false;
  // People as boxes (the benchmark's figures until issue 25 lands) or as skinned bodies.
  PeopleStyle people = PeopleStyle::kBoxes;

  // Throws InputError naming the field when a value is out of range.
  void Check() const;
};

// Image-level labels list a class when at least this many pixels per 640x480 (scaled with the
// image area, at least 1) show it: 200 px is 0.065 % of the image, a small but visible object.
int LabelMinPixels(int width, int height);

struct GenerateStats {
  int frames = 0;
  double seconds = 0.0;               // wall time of rendering and writing
  double mean_person_fraction = 0.0;  // mean over frames of person pixels / image pixels
  double max_person_fraction = 0.0;
  double frames_20_60 = 0.0;          // fraction of frames with 20-60 % person pixels
  double frames_over_10 = 0.0;        // fraction of frames with more than 10 % person pixels
  double mean_moving_fraction = 0.0;  // mean fraction of moving pixels
};

// Writes a preset sequence to options.out. Throws InputError on bad options or unwritable output.
GenerateStats GenerateSequence(const GeneratorOptions& options);

// Training mode: `count` independent frames (rgb/, labels.txt, and eval_only/class/ masks) from
// random scenes disjoint from the presets. Uses options.seed, out, textures_dir, width, height,
// texture_size, textures_per_kind, png_compression, sensor_noise.
GenerateStats GenerateTraining(const GeneratorOptions& options, int count);

// One rendered frame with its sensor effects and labels.
struct FrameData {
  cv::Mat rgb;       // CV_8UC3, RGB order, with noise (and blur)
  cv::Mat depth;     // CV_16UC1, factor 5000, 0 = hole (RGB-D only)
  cv::Mat depth_m;   // CV_32FC1 exact camera z (0: sky), before noise
  cv::Mat right;     // CV_8UC3 right image (stereo only)
  cv::Mat class_id;  // CV_8UC1
  cv::Mat instance;  // CV_16UC1
  cv::Mat moving;    // CV_8UC1, 255 on objects moving in this frame
  geometry::SE3 T_world_cam;
  double timestamp = 0.0;
};

// Renders frame `index` of `spec` (time index / rate).
FrameData RenderFrame(const SequenceSpec& spec, Renderer& renderer, int index,
                      const GeneratorOptions& options);

// Class names (not background) with at least min_pixels pixels in a class-id image.
std::vector<std::string> VisibleClasses(const cv::Mat& class_id, int min_pixels);

// A contact sheet: for each preset a row of `columns` frames, each as RGB, mask overlay and
// depth colour map, rendered at a reduced size. Writes a PNG to `path`.
void WriteContactSheet(const std::string& path, uint64_t seed, const std::string& textures_dir,
                       int columns, PeopleStyle people = PeopleStyle::kBoxes);

}  // namespace moslam::synth
