// The contact sheet of docs/SYNTH.md: every preset, a few frames each, as RGB, mask overlay
// (class colours, moving objects outlined) and depth colour map.
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/synth/generator.h"
#include "moslam/util/error.h"

namespace moslam::synth {
namespace {

// VOC-like colours per class id (RGB).
const cv::Vec3b kClassColours[kNumClasses] = {{0, 0, 0},     {192, 32, 32}, {32, 64, 224},
                                              {224, 192, 0}, {0, 192, 192}, {160, 64, 192}};

cv::Mat Overlay(const FrameData& f) {
  cv::Mat out = f.rgb.clone();
  for (int y = 0; y < out.rows; ++y) {
    for (int x = 0; x < out.cols; ++x) {
      const int c = f.class_id.at<uint8_t>(y, x);
      if (c == kBackground) continue;
      cv::Vec3b& p = out.at<cv::Vec3b>(y, x);
      for (int k = 0; k < 3; ++k) p[k] = static_cast<uint8_t>((p[k] + kClassColours[c][k]) / 2);
    }
  }
  // Outline moving pixels in white so the moving mask can be checked against the image.
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(f.moving.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  cv::drawContours(out, contours, -1, cv::Scalar(255, 255, 255), 1);
  return out;
}

cv::Mat DepthColour(const FrameData& f) {
  cv::Mat metres;
  if (!f.depth.empty()) {
    f.depth.convertTo(metres, CV_32F, 1.0 / 5000.0);
  } else {
    metres = f.depth_m;
  }
  const double max_m = f.depth.empty() ? 40.0 : 5.0;
  cv::Mat scaled;
  metres.convertTo(scaled, CV_8U, 255.0 / max_m);
  cv::Mat colour;
  cv::applyColorMap(scaled, colour, cv::COLORMAP_JET);
  cv::cvtColor(colour, colour, cv::COLOR_BGR2RGB);
  colour.setTo(cv::Scalar(0, 0, 0), metres <= 0);  // holes black
  return colour;
}

}  // namespace

void WriteContactSheet(const std::string& path, uint64_t seed, const std::string& textures_dir,
                       int columns, PeopleStyle people) {
  const int tile_w = 192;  // keeps the PNG under ~3 MB for the repository
  std::vector<cv::Mat> rows;
  for (const PresetInfo& preset : Presets()) {
    GeneratorOptions o;
    o.preset = preset.name;
    o.seed = seed;
    o.textures_dir = textures_dir;
    o.out = "(contact sheet)";
    o.people = people;
    const int w = preset.stereo ? 613 : 320, h = preset.stereo ? 185 : 240;
    o.width = w;
    o.height = h;
    o.texture_size = 256;
    TextureSet textures = TextureSet::Procedural(seed, 4, o.texture_size);
    if (!textures_dir.empty()) textures.AddPhotos(textures_dir, o.texture_size, 2, 0);
    const SequenceSpec spec = MakePreset(preset.name, seed, textures, w, h, people);
    Renderer renderer(w, h, textures);
    std::vector<cv::Mat> tiles;
    for (int c = 0; c < columns; ++c) {
      const int index = c * preset.default_frames / columns + 15;
      const FrameData f = RenderFrame(spec, renderer, index, o);
      cv::Mat stack;
      cv::vconcat(std::vector<cv::Mat>{f.rgb, Overlay(f), DepthColour(f)}, stack);
      cv::Mat resized;
      cv::resize(stack, resized, cv::Size(tile_w, stack.rows * tile_w / stack.cols), 0, 0,
                 cv::INTER_AREA);
      cv::copyMakeBorder(resized, resized, 2, 2, 2, 2, cv::BORDER_CONSTANT,
                         cv::Scalar(255, 255, 255));
      tiles.push_back(resized);
    }
    cv::Mat row;
    cv::hconcat(tiles, row);
    cv::Mat label(28, row.cols, CV_8UC3, cv::Scalar(40, 40, 40));
    cv::putText(label, fmt::format("{}: {}", preset.name, preset.description), cv::Point(6, 20),
                cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    rows.push_back(label);
    rows.push_back(row);
    spdlog::info("contact sheet: {} done", preset.name);
  }
  cv::Mat sheet;
  cv::vconcat(rows, sheet);
  cv::cvtColor(sheet, sheet, cv::COLOR_RGB2BGR);
  if (!cv::imwrite(path, sheet, {cv::IMWRITE_PNG_COMPRESSION, 9}))
    ThrowInput("synth: cannot write {}", path);
}

}  // namespace moslam::synth
