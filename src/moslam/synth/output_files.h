// Writing synthetic sequences to disk: the TUM RGB-D layout (Sturm et al. 2012) for indoor
// presets, the KITTI odometry layout (Geiger et al. 2012) for stereo ones, and the training
// layout. Per-frame masks are written beside the images (docs/SYNTH.md).
#pragma once

#include <fstream>
#include <string>
#include <vector>

#include "moslam/synth/generator.h"

namespace moslam::synth {

// "1000.033333": TUM-style stamps start at 1000 s.
std::string TumStamp(double t);
inline constexpr double kTumStartTime = 1000.0;

// Lines "<id> <name> <movable 0|1>", one per class.
void WriteClassesFile(const std::string& path);

// The ORB-SLAM2 settings of a sequence (RGB-D: Camera.bf 40, ThDepth 40, DepthMapFactor 5000;
// stereo: Camera.bf = baseline * fx, ThDepth 35).
std::string SettingsYaml(const SequenceSpec& spec);

// Frames must be written in order, from one thread.
class OutputWriter {
 public:
  OutputWriter(const std::string& folder, const SequenceSpec& spec,
               const GeneratorOptions& options);
  void WriteFrame(const FrameData& frame);
  void Finish();

 private:
  void WritePng(const std::string& relative, const cv::Mat& image);
  std::string folder_;
  bool stereo_;
  bool exact_depth_;
  std::vector<int> png_params_;
  int label_min_pixels_;
  int index_ = 0;
  bool have_first_ = false;
  geometry::SE3 T_world_first_;  // KITTI poses are relative to the first camera
  std::ofstream rgb_, depth_, gt_, assoc_, labels_, times_, poses_;
};

class TrainingWriter {
 public:
  TrainingWriter(const std::string& folder, const GeneratorOptions& options, int width, int height);
  void WriteFrame(const FrameData& frame);
  void Finish();

 private:
  std::string folder_;
  std::vector<int> png_params_;
  int label_min_pixels_;
  int index_ = 0;
  std::ofstream labels_;
};

}  // namespace moslam::synth
