#include "moslam/synth/generator.h"

#include <chrono>
#include <cmath>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <thread>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/synth/output_files.h"
#include "moslam/synth/rng.h"
#include "moslam/util/bounded_queue.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/util/progress.h"

namespace moslam::synth {
namespace {

namespace fs = std::filesystem;
constexpr uint64_t kNoiseStream = 0x5E45;
constexpr int kBlurSamples = 4;

cv::Mat MovingMask(const cv::Mat& instance, const std::vector<uint16_t>& moving) {
  cv::Mat mask(instance.size(), CV_8UC1, cv::Scalar(0));
  if (moving.empty()) return mask;
  std::vector<uint8_t> lut(65536, 0);
  for (uint16_t id : moving) lut[id] = 255;
  for (int y = 0; y < instance.rows; ++y) {
    const uint16_t* in = instance.ptr<uint16_t>(y);
    uint8_t* out = mask.ptr<uint8_t>(y);
    for (int x = 0; x < instance.cols; ++x) out[x] = lut[in[x]];
  }
  return mask;
}

TextureSet LoadTextures(const GeneratorOptions& o, uint64_t seed, int photo_phase) {
  TextureSet set = TextureSet::Procedural(seed, o.textures_per_kind, o.texture_size);
  if (!o.textures_dir.empty()) set.AddPhotos(o.textures_dir, o.texture_size, 2, photo_phase);
  return set;
}

// Person-coverage statistics, accumulated on the render thread.
struct Coverage {
  double sum = 0, max = 0, sum_moving = 0;
  int n = 0, in_20_60 = 0, over_10 = 0;
  void Add(const FrameData& f) {
    const double total = static_cast<double>(f.class_id.total());
    const double person = cv::countNonZero(f.class_id == kPerson) / total;
    sum += person;
    max = std::max(max, person);
    in_20_60 += person >= 0.2 && person <= 0.6;
    over_10 += person > 0.1;
    sum_moving += cv::countNonZero(f.moving) / total;
    ++n;
  }
  void Fill(GenerateStats* s) const {
    s->frames = n;
    if (n == 0) return;
    s->mean_person_fraction = sum / n;
    s->max_person_fraction = max;
    s->frames_20_60 = static_cast<double>(in_20_60) / n;
    s->frames_over_10 = static_cast<double>(over_10) / n;
    s->mean_moving_fraction = sum_moving / n;
  }
};

// Runs render(i) for i in [0, n) on this thread and write(frame) on a second thread, through a
// bounded queue so that PNG encoding overlaps rendering. Rethrows the writer's exception.
void Pipeline(int n, const std::function<FrameData(int)>& render,
              const std::function<void(const FrameData&)>& write, bool progress_on,
              const std::string& label, Coverage* coverage) {
  BoundedQueue<FrameData> queue(4);
  std::exception_ptr error;
  std::thread writer([&] {
    try {
      while (auto frame = queue.Pop()) write(*frame);
    } catch (...) {
      error = std::current_exception();
      queue.Close();
    }
  });
  Progress progress(label, static_cast<size_t>(n), progress_on ? 2.0 : 1e9, "frames");
  try {
    for (int i = 0; i < n; ++i) {
      FrameData frame = render(i);
      coverage->Add(frame);
      if (!queue.Push(std::move(frame))) break;
      progress.Update(static_cast<size_t>(i + 1));
    }
  } catch (...) {
    queue.Close();
    writer.join();
    throw;
  }
  queue.Close();
  writer.join();
  if (error) std::rethrow_exception(error);
  if (progress_on) progress.Finish();
}

}  // namespace

void GeneratorOptions::Check() const {
  if (out.empty()) ThrowInput("synth: --out (output folder) is required");
  if (frames < 0) ThrowInput("synth: --frames must be >= 0, got {}", frames);
  if ((width == 0) != (height == 0) || width < 0 || height < 0 || width > 8192 || height > 8192) {
    ThrowInput("synth: --width and --height must both be given and in 1..8192 (got {}x{})", width,
               height);
  }
  if (texture_size < 64 || (texture_size & (texture_size - 1)) != 0 || texture_size > 4096) {
    ThrowInput("synth: texture_size must be a power of two in 64..4096, got {}", texture_size);
  }
  if (textures_per_kind < 1 || textures_per_kind > 64) {
    ThrowInput("synth: --textures-per-kind must be in 1..64, got {}", textures_per_kind);
  }
  if (png_compression < 0 || png_compression > 9) {
    ThrowInput("synth: png_compression must be in 0..9, got {}", png_compression);
  }
}

int LabelMinPixels(int width, int height) {
  return std::max(1, static_cast<int>(std::lround(200.0 * width * height / (640.0 * 480.0))));
}

std::vector<std::string> VisibleClasses(const cv::Mat& class_id, int min_pixels) {
  std::vector<int> count(256, 0);
  for (int y = 0; y < class_id.rows; ++y) {
    const uint8_t* row = class_id.ptr<uint8_t>(y);
    for (int x = 0; x < class_id.cols; ++x) ++count[row[x]];
  }
  std::vector<std::string> names;
  for (int c = 1; c < kNumClasses; ++c) {
    if (count[static_cast<size_t>(c)] >= min_pixels) names.push_back(ClassName(c));
  }
  return names;
}

FrameData RenderFrame(const SequenceSpec& spec, Renderer& renderer, int index,
                      const GeneratorOptions& options) {
  FrameData f;
  const double dt = 1.0 / spec.info.rate_hz;
  const double t = index * dt;
  f.timestamp = t;
  f.T_world_cam = spec.T_world_cam(t);
  const geometry::SE3 T_cam_world = f.T_world_cam.Inverse();
  RenderOutput out;
  renderer.Render(spec.world.BoxesAt(t), spec.world.MeshesAt(t), spec.camera, T_cam_world,
                  spec.lighting, &out);
  if (options.motion_blur) {
    // Exposure of 1/60 s centred on t: the mean of kBlurSamples renders (colour only; depth and
    // labels stay those of time t, as a Kinect's depth is not blurred like its colour).
    cv::Mat sum;
    out.rgb.convertTo(sum, CV_32FC3);
    RenderOutput sub;
    for (int k = 0; k < kBlurSamples; ++k) {
      if (k == kBlurSamples / 2) continue;
      const double ts = t + (static_cast<double>(k) / (kBlurSamples - 1) - 0.5) / 60.0;
      renderer.Render(spec.world.BoxesAt(ts), spec.world.MeshesAt(ts), spec.camera,
                      spec.T_world_cam(ts).Inverse(), spec.lighting, &sub);
      cv::accumulate(sub.rgb, sum);
    }
    sum.convertTo(out.rgb, CV_8UC3, 1.0 / kBlurSamples);
  }
  const uint64_t noise_seed = Rng::Mix(options.seed * 31 + kNoiseStream);
  f.rgb = out.rgb;
  ColourNoiseOptions colour;
  colour.enabled = options.sensor_noise;
  AddColourNoise(&f.rgb, colour, noise_seed, static_cast<uint64_t>(index) * 2);
  f.depth_m = out.depth;
  f.class_id = out.class_id;
  f.instance = out.instance;
  f.moving = MovingMask(out.instance, spec.world.MovingInstances(t, dt));
  if (spec.info.stereo) {
    // The right camera sits baseline metres along the left camera's +x.
    const geometry::SE3 T_left_right(Eigen::Quaterniond::Identity(),
                                     Eigen::Vector3d(spec.baseline_m, 0, 0));
    RenderOutput right;
    renderer.Render(spec.world.BoxesAt(t), spec.world.MeshesAt(t), spec.camera,
                    (f.T_world_cam * T_left_right).Inverse(), spec.lighting, &right);
    f.right = right.rgb;
    AddColourNoise(&f.right, colour, noise_seed, static_cast<uint64_t>(index) * 2 + 1);
  } else {
    DepthNoiseOptions depth;
    depth.enabled = options.sensor_noise;
    f.depth = KinectDepth(out.depth, depth, 5000.0, noise_seed, static_cast<uint64_t>(index));
  }
  return f;
}

GenerateStats GenerateSequence(const GeneratorOptions& options) {
  options.Check();
  const PresetInfo& info = FindPreset(options.preset);
  const TextureSet textures = LoadTextures(options, options.seed, 0);
  const SequenceSpec spec = MakePreset(options.preset, options.seed, textures, options.width,
                                       options.height, options.people);
  const int n = options.frames > 0 ? options.frames : info.default_frames;
  Renderer renderer(spec.camera.width, spec.camera.height, textures);
  spdlog::info("synth: {} seed {} -> {} ({} frames {}x{}, {} textures, people as {}, {})",
               options.preset, options.seed, options.out, n, spec.camera.width, spec.camera.height,
               textures.textures().size(), PeopleStyleName(options.people),
               renderer.RendererName());
  OutputWriter writer(options.out, spec, options);
  const auto start = std::chrono::steady_clock::now();
  Coverage coverage;
  Pipeline(
      n, [&](int i) { return RenderFrame(spec, renderer, i, options); },
      [&](const FrameData& f) { writer.WriteFrame(f); }, options.progress, "synth " + info.name,
      &coverage);
  writer.Finish();
  GenerateStats stats;
  coverage.Fill(&stats);
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

GenerateStats GenerateTraining(const GeneratorOptions& options, int count) {
  options.Check();
  if (count <= 0) ThrowInput("synth: --train needs a positive frame count, got {}", count);
  const int w = options.width > 0 ? options.width : 640,
            h = options.height > 0 ? options.height : 480;
  // Procedural textures from another seed stream than the presets', photographs from the other
  // half of the folder (presets use even-numbered files, training odd-numbered ones).
  const TextureSet textures = LoadTextures(options, Rng::Mix(options.seed + 0x7AA1), 1);
  Renderer renderer(w, h, textures);
  TrainingWriter writer(options.out, options, w, h);
  const auto start = std::chrono::steady_clock::now();
  Coverage coverage;
  Pipeline(
      count,
      [&](int i) {
        const SequenceSpec spec =
            MakeTrainingScene(Rng::Mix(options.seed * 1000003ULL + static_cast<uint64_t>(i)),
                              textures, w, h, options.people);
        GeneratorOptions frame_options = options;
        frame_options.seed = options.seed * 7919 + static_cast<uint64_t>(i);
        return RenderFrame(spec, renderer, 0, frame_options);
      },
      [&](const FrameData& f) { writer.WriteFrame(f); }, options.progress, "synth train",
      &coverage);
  writer.Finish();
  GenerateStats stats;
  coverage.Fill(&stats);
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

}  // namespace moslam::synth
