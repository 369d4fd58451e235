// Tests of `moslam synth` on short, small sequences (procedural textures only, no shared data).
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/io/dataset.h"
#include "moslam/io/image.h"
#include "moslam/io/kitti.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/synth/check.h"
#include "moslam/synth/generator.h"
#include "moslam/synth/output_files.h"
#include "moslam/synth/presets.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::synth {
namespace {

namespace fs = std::filesystem;

GeneratorOptions Small(const std::string& preset, const std::string& out, int frames) {
  GeneratorOptions o;
  o.preset = preset;
  o.seed = 3;
  o.out = out;
  o.frames = frames;
  o.width = 320;
  o.height = 240;
  o.texture_size = 128;
  o.progress = false;
  return o;
}

std::string ReadAll(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Every regular file under `root`, relative path -> contents.
std::map<std::string, std::string> Snapshot(const std::string& root) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    if (e.is_regular_file()) files[fs::relative(e.path(), root).string()] = ReadAll(e.path());
  }
  return files;
}

std::vector<std::vector<std::string>> DataLines(const fs::path& path) {
  std::ifstream f(path);
  std::vector<std::vector<std::string>> lines;
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    std::vector<std::string> fields;
    for (std::string w; s >> w;) fields.push_back(w);
    lines.push_back(fields);
  }
  return lines;
}

TEST(Synth, SamePresetSeedAndTexturesGiveByteIdenticalOutput) {
  testing::TempDir a, b;
  GenerateSequence(Small("w_xyz", a.path(), 4));
  GenerateSequence(Small("w_xyz", b.path(), 4));
  const auto fa = Snapshot(a.path()), fb = Snapshot(b.path());
  ASSERT_EQ(fa.size(), fb.size());
  ASSERT_GT(fa.size(), 20u);
  for (const auto& [name, contents] : fa) {
    ASSERT_TRUE(fb.count(name)) << name;
    EXPECT_TRUE(contents == fb.at(name)) << name << " differs between two runs";
  }
  // A different seed gives a different sequence.
  testing::TempDir c;
  GeneratorOptions other = Small("w_xyz", c.path(), 1);
  other.seed = 4;
  GenerateSequence(other);
  const std::string first = "rgb/" + TumStamp(0.0) + ".png";
  EXPECT_NE(ReadAll(fs::path(a.path()) / first), ReadAll(fs::path(c.path()) / first));
}

TEST(Synth, TumLayoutLoadsWithTheProjectsReaderAndSettingsLoader) {
  testing::TempDir dir;
  GenerateSequence(Small("w_static", dir.path(), 5));
  for (const char* name : {"rgb.txt", "depth.txt", "groundtruth.txt", "associations.txt",
                           "settings.yaml", "classes.txt", "labels.txt"}) {
    EXPECT_TRUE(fs::exists(fs::path(dir.path()) / name)) << name;
  }
  const io::Sequence seq = io::ReadDataset(dir.path());
  ASSERT_EQ(seq.size(), 5u);
  EXPECT_EQ(seq.sensor, io::SensorType::kRgbD);
  ASSERT_TRUE(seq.ground_truth_path.has_value());
  EXPECT_NEAR(seq.frames[0].timestamp, 1000.0, 1e-9);
  EXPECT_NEAR(seq.frames[1].timestamp - seq.frames[0].timestamp, 1.0 / 30.0, 1e-6);
  io::DatasetOptions with_assoc;
  with_assoc.tum.associations_path = (fs::path(dir.path()) / "associations.txt").string();
  EXPECT_EQ(io::ReadDataset(dir.path(), with_assoc).size(), 5u);

  const io::FrameImages images = io::LoadFrameImages(seq.frames[2], io::ColourMode::kColour);
  EXPECT_EQ(images.left.cols, 320);
  EXPECT_EQ(images.left.rows, 240);
  ASSERT_EQ(images.depth.type(), CV_32FC1);
  double lo = 0, hi = 0;
  cv::minMaxLoc(images.depth, &lo, &hi);
  EXPECT_GT(hi, 1.0);  // metres: the room is a few metres deep
  EXPECT_LT(hi, 5.5);

  const io::OrbSlamSettings s = io::LoadOrbSlamSettings(
      (fs::path(dir.path()) / "settings.yaml").string(), io::SensorType::kRgbD);
  const camera::PinholeOptions expected = TumCamera(320, 240);
  EXPECT_NEAR(s.camera.fx, expected.fx, 1e-6);
  EXPECT_NEAR(s.camera.cy, expected.cy, 1e-6);
  EXPECT_EQ(s.camera.width, 320);
  EXPECT_DOUBLE_EQ(s.depth_map_factor, 5000.0);
  EXPECT_DOUBLE_EQ(s.bf, 40.0);
  // The shipped settings file is the one a 640x480 preset writes.
  const camera::PinholeOptions full = TumCamera(640, 480);
  const io::OrbSlamSettings shipped =
      io::LoadOrbSlamSettings("configs/Synthetic_RGBD.yaml", io::SensorType::kRgbD);
  EXPECT_NEAR(shipped.camera.fx, full.fx, 1e-6);
  EXPECT_NEAR(shipped.camera.cx, full.cx, 1e-6);
}

TEST(Synth, StaticPixelsReprojectWithGroundTruthPosesAndDepth) {
  testing::TempDir dir;
  GeneratorOptions o = Small("w_xyz", dir.path(), 12);
  o.write_exact_depth = true;
  GenerateSequence(o);
  const ReprojectionStats s = CheckReprojection(dir.path(), 6, 2, 2);
  ASSERT_TRUE(s.exact_depth);
  ASSERT_GT(s.checked, 10000);
  // Exact depth: the same surface to within the PNG's 0.2 mm quantization for most pixels; the
  // tail is pixels next to depth edges.
  EXPECT_LT(s.depth_median, 0.0005);
  EXPECT_LT(s.depth_p90, 0.002);
  // Same texture: colour noise (sigma 2) and resampling only.
  EXPECT_LT(s.grey_median, 6.0);
  // Noisy Kinect depth agrees with the re-projected depth within its noise model.
  EXPECT_GT(s.noisy_within_3sigma, 0.95);
}

TEST(Synth, WrongPosesFailTheReprojectionCheck) {
  testing::TempDir dir;
  GeneratorOptions o = Small("w_xyz", dir.path(), 8);
  o.write_exact_depth = true;
  GenerateSequence(o);
  const ReprojectionStats right = CheckReprojection(dir.path(), 1, 1, 2);
  // Shift every other ground-truth position by 5 cm in x and y (y is the viewing direction): the
  // check must see it, in depth and in colour (a lateral shift along a plane keeps the depth).
  const fs::path gt = fs::path(dir.path()) / "groundtruth.txt";
  std::string out;
  int n = 0;
  for (const auto& f : DataLines(gt)) {
    const double shift = 0.05 * (n++ % 2);
    out += f[0] + " " + std::to_string(std::stod(f[1]) + shift) + " " +
           std::to_string(std::stod(f[2]) + shift);
    for (size_t k = 3; k < f.size(); ++k) out += " " + f[k];
    out += "\n";
  }
  std::ofstream(gt) << out;
  const ReprojectionStats wrong = CheckReprojection(dir.path(), 1, 1, 2);
  EXPECT_LT(right.depth_median, 0.0005);
  EXPECT_GT(wrong.depth_median, 0.01);
  EXPECT_GT(wrong.grey_median, 2 * right.grey_median);
}

TEST(Synth, MasksAndLabelsAreConsistent) {
  testing::TempDir dir;
  GeneratorOptions o = Small("w_halfsphere", dir.path(), 30);
  o.width = 160;
  o.height = 120;
  GenerateSequence(o);
  const fs::path root(dir.path());
  // classes.txt: the fixed ids, names and movable flags.
  const auto classes = DataLines(root / "classes.txt");
  ASSERT_EQ(classes.size(), static_cast<size_t>(kNumClasses));
  EXPECT_EQ(classes[1][1], "person");
  EXPECT_EQ(classes[1][2], "1");
  EXPECT_EQ(classes[2][1], "car");
  EXPECT_EQ(classes[3][2], "0");
  const int min_pixels = LabelMinPixels(160, 120);
  const auto labels = DataLines(root / "labels.txt");
  ASSERT_EQ(labels.size(), 30u);
  int person_frames = 0;
  for (const auto& line : labels) {
    const std::string stem = fs::path(line[0]).stem().string();
    const cv::Mat cls =
        cv::imread((root / "class" / (stem + ".png")).string(), cv::IMREAD_UNCHANGED);
    const cv::Mat inst =
        cv::imread((root / "instance" / (stem + ".png")).string(), cv::IMREAD_UNCHANGED);
    const cv::Mat moving =
        cv::imread((root / "moving" / (stem + ".png")).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(cls.type(), CV_8UC1);
    ASSERT_EQ(inst.type(), CV_16UC1);
    ASSERT_EQ(moving.type(), CV_8UC1);
    // Labels are exactly the classes with at least min_pixels pixels.
    const std::vector<std::string> expected = VisibleClasses(cls, min_pixels);
    EXPECT_EQ(std::vector<std::string>(line.begin() + 1, line.end()), expected) << stem;
    person_frames += std::count(expected.begin(), expected.end(), "person") > 0;
    for (int y = 0; y < cls.rows; ++y) {
      for (int x = 0; x < cls.cols; ++x) {
        const int c = cls.at<uint8_t>(y, x), i = inst.at<uint16_t>(y, x);
        const int m = moving.at<uint8_t>(y, x);
        ASSERT_TRUE(m == 0 || m == 255);
        ASSERT_EQ(c == kBackground, i == 0) << stem << " at " << x << "," << y;
        if (m) {
          ASSERT_TRUE(IsMovableClass(c)) << stem << " moving pixel of class " << c;
        }
      }
    }
    // Walking people move in every frame: their pixels are all moving.
    EXPECT_EQ(cv::countNonZero(cls == kPerson), cv::countNonZero(moving)) << stem;
  }
  EXPECT_GT(person_frames, 0);
}

TEST(Synth, WalkingPresetPeopleCoverALargePartOfTheView) {
  testing::TempDir dir;
  GeneratorOptions o = Small("w_xyz", dir.path(), 90);
  o.width = 160;
  o.height = 120;
  const GenerateStats s = GenerateSequence(o);
  EXPECT_EQ(s.frames, 90);
  EXPECT_GT(s.mean_person_fraction, 0.05);
  EXPECT_GT(s.max_person_fraction, 0.2);
  EXPECT_LT(s.max_person_fraction, 0.9);
  EXPECT_GT(s.frames_over_10, 0.3);
}

TEST(Synth, StaticPresetIsWalkingXyzWithoutPeople) {
  testing::TempDir a, b;
  const GenerateStats s = GenerateSequence(Small("static_xyz", a.path(), 3));
  EXPECT_EQ(s.mean_person_fraction, 0.0);
  EXPECT_EQ(s.mean_moving_fraction, 0.0);
  GenerateSequence(Small("w_xyz", b.path(), 3));
  // Same room and camera path as w_xyz: identical ground truth.
  EXPECT_EQ(DataLines(fs::path(a.path()) / "groundtruth.txt"),
            DataLines(fs::path(b.path()) / "groundtruth.txt"));
}

// The aliasing presets' camera paths (docs/SYNTH.md): the straight ones never come back to a
// place (so any loop closed there is false), the rings come back to their start once, pointing
// the same way (so exactly one loop is true).
TEST(Synth, AliasingPresetsRevisitAPlaceOnlyOnTheRings) {
  const TextureSet textures = TextureSet::Procedural(1, 4, 64);
  for (const char* name : {"street_repeat", "street_repeat_loop", "corridor", "corridor_loop"}) {
    for (uint64_t seed : {1u, 2u}) {
      const SequenceSpec spec = MakePreset(name, seed, textures);
      const bool ring = std::string(name).find("loop") != std::string::npos;
      const double rate = spec.info.rate_hz, scale = spec.info.stereo ? 10.0 : 1.0;
      std::vector<geometry::SE3> poses;
      for (int i = 0; i < spec.info.default_frames; ++i)
        poses.push_back(spec.T_world_cam(i / rate));
      // The closest earlier pose at least 10 s back, over the whole path.
      double closest = 1e9, angle_there = 0.0;
      for (size_t i = 0; i < poses.size(); ++i) {
        for (size_t j = 0; j + static_cast<size_t>(10 * rate) < i; ++j) {
          const double d = (poses[i].translation() - poses[j].translation()).norm();
          if (d < closest) {
            closest = d;
            angle_there =
                Eigen::AngleAxisd(poses[i].rotation() * poses[j].rotation().inverse()).angle();
          }
        }
      }
      SCOPED_TRACE(std::string(name) + " seed " + std::to_string(seed));
      if (ring) {
        EXPECT_LT(closest, 0.5 * scale);  // metres: 5 m on the street, 0.5 m in the corridor
        EXPECT_LT(angle_there, 45.0 * M_PI / 180.0);  // the walker looks +-20 degrees about
      } else {
        // Every place is new: the path is a straight line, nothing 10 s back is near.
        EXPECT_GT(closest, 5.0 * scale);
      }
    }
  }
}

// Issue 24's unknown mover: the cart stands still at its stops and moves between them (it is a
// moving instance only then), it is labelled background (no card knows it), and it fills a good
// part of the view when it passes in front of the camera.
TEST(Synth, UnknownMoverCartStopsMovesAndIsBackground) {
  const TextureSet textures = TextureSet::Procedural(1, 4, 64);
  const SequenceSpec spec = MakePreset("unknown_mover", 5, textures);
  ASSERT_EQ(spec.world.actors.size(), 1u);
  const Actor& actor = spec.world.actors.front();
  ASSERT_EQ(actor.kind, ActorKind::kCart);
  const Cart& cart = actor.cart;
  // At the first stop for its whole dwell, then on the way: exactly where a leg starts.
  EXPECT_EQ(cart.PositionAt(0.0), cart.stops[0]);
  EXPECT_EQ(cart.PositionAt(0.99 * cart.dwell_s[0]), cart.stops[0]);
  EXPECT_GT((cart.PositionAt(cart.dwell_s[0] + 0.5) - cart.stops[0]).norm(), 0.01);
  double fastest = 0.0;
  bool stood_still = false, moved = false;
  for (double t = 0.0; t < 30.0; t += 1.0 / 30) {
    const double speed = (cart.PositionAt(t + 1.0 / 30) - cart.PositionAt(t)).norm() * 30;
    fastest = std::max(fastest, speed);
    const std::vector<uint16_t> moving = spec.world.MovingInstances(t, 1.0 / 30);
    stood_still = stood_still || moving.empty();
    moved = moved || (moving.size() == 1 && moving[0] == actor.instance);
  }
  EXPECT_LE(fastest, cart.max_speed * 1.01);  // the half-cosine profile peaks at max_speed
  EXPECT_TRUE(stood_still);
  EXPECT_TRUE(moved);
  std::vector<Box> boxes;
  actor.AppendBoxes(0.0, &boxes);
  for (const Box& b : boxes) EXPECT_EQ(b.class_id, kBackground);
  // Rendered at the middle stop (in front of the camera): a large share of the image, not moving.
  const SequenceSpec small = MakePreset("unknown_mover", 5, textures, 160, 120);
  Renderer renderer(160, 120, textures);
  const double at_middle =
      cart.dwell_s[0] + M_PI * (cart.stops[1] - cart.stops[0]).norm() / (2 * cart.max_speed) + 0.5;
  const FrameData f = RenderFrame(small, renderer, static_cast<int>(at_middle * 30),
                                  Small("unknown_mover", "unused", 1));
  EXPECT_GT(cv::countNonZero(f.instance == actor.instance), 0.15 * f.instance.total());
  EXPECT_EQ(cv::countNonZero(f.moving), 0);
  EXPECT_EQ(cv::countNonZero((f.class_id != kBackground) & (f.instance == actor.instance)), 0);
}

TEST(Synth, SeatedPresetPeopleMoveALittle) {
  testing::TempDir dir;
  GeneratorOptions o = Small("s_static", dir.path(), 3);
  const GenerateStats s = GenerateSequence(o);
  EXPECT_GT(s.mean_person_fraction, 0.01);
  EXPECT_GT(s.mean_moving_fraction, 0.0);  // seated people gesture: their pixels move
}

TEST(Synth, KittiLayoutLoadsWithTheProjectsReader) {
  testing::TempDir dir;
  GeneratorOptions o = Small("kitti_cars", dir.path(), 4);
  o.width = 400;
  o.height = 120;
  GenerateSequence(o);
  const io::Sequence seq = io::ReadDataset(dir.path());
  ASSERT_EQ(seq.size(), 4u);
  EXPECT_EQ(seq.sensor, io::SensorType::kStereo);
  ASSERT_TRUE(seq.calibration.has_value());
  EXPECT_NEAR(seq.calibration->baseline(), 0.537, 1e-6);
  ASSERT_TRUE(seq.ground_truth_path.has_value());
  const io::FrameImages images = io::LoadFrameImages(seq.frames[1], io::ColourMode::kGrey);
  EXPECT_EQ(images.left.cols, 400);
  EXPECT_EQ(images.right.rows, 120);
  EXPECT_TRUE(fs::exists(fs::path(dir.path()) / "class" / "000001.png"));
  const io::OrbSlamSettings s = io::LoadOrbSlamSettings(
      (fs::path(dir.path()) / "settings.yaml").string(), io::SensorType::kStereo);
  EXPECT_NEAR(s.Baseline(), 0.537, 1e-6);
  io::LoadOrbSlamSettings("configs/Synthetic_Stereo.yaml", io::SensorType::kStereo);
}

TEST(Synth, TrainingModeWritesLabelsAndEvalOnlyMasks) {
  testing::TempDir dir;
  GeneratorOptions o = Small("", dir.path(), 0);
  const GenerateStats s = GenerateTraining(o, 5);
  EXPECT_EQ(s.frames, 5);
  const fs::path root(dir.path());
  const auto labels = DataLines(root / "labels.txt");
  ASSERT_EQ(labels.size(), 5u);
  for (const auto& line : labels) {
    EXPECT_TRUE(fs::exists(root / line[0]));
    const cv::Mat cls =
        cv::imread((root / "eval_only" / "class" / fs::path(line[0]).filename()).string(),
                   cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(cls.empty());
    EXPECT_EQ(std::vector<std::string>(line.begin() + 1, line.end()),
              VisibleClasses(cls, LabelMinPixels(320, 240)));
    const cv::Mat depth =
        cv::imread((root / "depth" / fs::path(line[0]).filename()).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(depth.type(), CV_16UC1);
    EXPECT_EQ(depth.size(), cls.size());
    // The Kinect model's range (0.5-5 m, on the true depth; disparity quantization moves a
    // reading at 5 m by up to ~0.1 m) in PNG units of 1/5000 m; rooms of 4-8 m leave far walls
    // without depth, but never the whole image.
    EXPECT_GT(cv::countNonZero(depth), static_cast<int>(depth.total() / 10));
    double lo = 0, hi = 0;
    cv::minMaxLoc(depth, &lo, &hi, nullptr, nullptr, depth > 0);
    EXPECT_GE(lo, 0.45 * 5000);
    EXPECT_LE(hi, 5.25 * 5000);
  }
  // Training frames are not the presets' frames.
  EXPECT_FALSE(fs::exists(root / "rgb.txt"));
}

TEST(Synth, MotionBlurChangesColourOnlyWhereThingsMove) {
  const TextureSet textures = TextureSet::Procedural(3, 1, 128);
  const SequenceSpec spec = MakePreset("w_static", 3, textures, 160, 120);
  Renderer renderer(160, 120, textures);
  GeneratorOptions sharp = Small("w_static", "unused", 1);
  sharp.sensor_noise = false;
  GeneratorOptions blurred = sharp;
  blurred.motion_blur = true;
  // A frame with a walker in view.
  int index = 0;
  FrameData a;
  for (; index < 300; index += 10) {
    a = RenderFrame(spec, renderer, index, sharp);
    if (cv::countNonZero(a.moving) > 200) break;
  }
  ASSERT_GT(cv::countNonZero(a.moving), 200);
  const FrameData b = RenderFrame(spec, renderer, index, blurred);
  EXPECT_EQ(cv::countNonZero(a.class_id != b.class_id), 0);  // labels of the frame's own time
  cv::Mat diff;
  cv::absdiff(a.rgb, b.rgb, diff);
  cv::Mat grey_diff;
  cv::cvtColor(diff, grey_diff, cv::COLOR_RGB2GRAY);
  EXPECT_GT(cv::countNonZero(grey_diff > 10), 50);  // moving limbs are smeared
}

TEST(Synth, OptionsAreChecked) {
  GeneratorOptions o = Small("w_xyz", "", 1);
  EXPECT_THROW(o.Check(), InputError);
  o.out = "/tmp/x";
  o.width = 100;
  o.height = 0;
  EXPECT_THROW(o.Check(), InputError);
  EXPECT_THROW(FindPreset("walking"), InputError);
  o.height = 100;
  EXPECT_NO_THROW(o.Check());
  o.textures_per_kind = 0;
  EXPECT_THROW(o.Check(), InputError);
  o.textures_per_kind = 65;
  EXPECT_THROW(o.Check(), InputError);
}

TEST(Synth, MoreTexturesPerKindExtendTheDefaultSet) {
  // The first textures of each kind do not depend on how many there are, so the presets' look
  // (4 a kind) is kept inside a larger training set.
  const TextureSet four = TextureSet::Procedural(7, 4, 128);
  const TextureSet six = TextureSet::Procedural(7, 6, 128);
  int differing_extra = 0;
  for (int k = 0; k < static_cast<int>(TextureKind::kCount); ++k) {
    const auto kind = static_cast<TextureKind>(k);
    ASSERT_EQ(four.OfKind(kind).size(), 4u);
    ASSERT_EQ(six.OfKind(kind).size(), 6u);
    for (int i = 0; i < 4; ++i) {
      const cv::Mat a = four.textures()[four.OfKind(kind)[i]].rgb;
      const cv::Mat b = six.textures()[six.OfKind(kind)[i]].rgb;
      EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "kind " << k << " texture " << i;
    }
    for (int i : six.OfKind(kind)) {
      // Every texture has content (fine noise once rendered small textures black).
      EXPECT_GT(cv::norm(six.textures()[i].rgb, cv::NORM_INF), 0.0) << six.textures()[i].name;
    }
    const cv::Mat first = six.textures()[six.OfKind(kind)[0]].rgb;
    const cv::Mat extra = six.textures()[six.OfKind(kind)[5]].rgb;
    differing_extra += cv::norm(first, extra, cv::NORM_INF) > 0;
  }
  EXPECT_EQ(differing_extra, static_cast<int>(TextureKind::kCount));
}

}  // namespace
}  // namespace moslam::synth
