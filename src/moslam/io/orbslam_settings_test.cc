#include "moslam/io/orbslam_settings.h"

#include <map>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/io/io_test_util.h"

namespace moslam::io {
namespace {

using test::ErrorOf;
using ::testing::AllOf;
using ::testing::HasSubstr;

// An RGB-D settings file in ORB-SLAM2's layout, as ordered key -> value text. Tests edit the map
// and write it with SettingsText.
using Keys = std::vector<std::pair<std::string, std::string>>;

Keys RgbdKeys() {
  return {{"Camera.fx", "517.306408"},
          {"Camera.fy", "516.469215"},
          {"Camera.cx", "318.643040"},
          {"Camera.cy", "255.313989"},
          {"Camera.k1", "0.262383"},
          {"Camera.k2", "-0.953104"},
          {"Camera.p1", "-0.005358"},
          {"Camera.p2", "0.002628"},
          {"Camera.k3", "1.163314"},
          {"Camera.width", "640"},
          {"Camera.height", "480"},
          {"Camera.fps", "30.0"},
          {"Camera.bf", "40.0"},
          {"Camera.RGB", "1"},
          {"ThDepth", "40.0"},
          {"DepthMapFactor", "5000.0"},
          {"ORBextractor.nFeatures", "1000"},
          {"ORBextractor.scaleFactor", "1.2"},
          {"ORBextractor.nLevels", "8"},
          {"ORBextractor.iniThFAST", "20"},
          {"ORBextractor.minThFAST", "7"},
          {"Viewer.KeyFrameSize", "0.05"},
          {"Viewer.PointSize", "2"}};
}

std::string SettingsText(const Keys& keys) {
  std::string text = "%YAML:1.0\n# test settings\n";
  for (const auto& [key, value] : keys) text += key + ": " + value + "\n";
  return text;
}

Keys Without(Keys keys, const std::string& key) {
  keys.erase(
      std::remove_if(keys.begin(), keys.end(), [&](const auto& kv) { return kv.first == key; }),
      keys.end());
  return keys;
}

Keys With(Keys keys, const std::string& key, const std::string& value) {
  for (auto& kv : keys) {
    if (kv.first == key) {
      kv.second = value;
      return keys;
    }
  }
  keys.emplace_back(key, value);
  return keys;
}

TEST(OrbSlamSettings, DefaultsAreDocumentedValues) {
  const OrbSlamSettings s;
  EXPECT_DOUBLE_EQ(s.fps, 30.0);
  EXPECT_TRUE(s.rgb);
  EXPECT_DOUBLE_EQ(s.bf, 0.0);
  EXPECT_DOUBLE_EQ(s.th_depth, 35.0);
  EXPECT_DOUBLE_EQ(s.depth_map_factor, 5000.0);
  EXPECT_EQ(s.orb.num_features, 1000);
  EXPECT_DOUBLE_EQ(s.orb.scale_factor, 1.2);
  EXPECT_EQ(s.orb.num_levels, 8);
  EXPECT_EQ(s.orb.ini_th_fast, 20);
  EXPECT_EQ(s.orb.min_th_fast, 7);
  EXPECT_NO_THROW(s.orb.Check());
  EXPECT_FALSE(s.rectification.has_value());
}

TEST(LoadOrbSlamSettings, ReadsAnRgbdFile) {
  testing::TempDir dir;
  const OrbSlamSettings s =
      LoadOrbSlamSettings(dir.Write("tum1.yaml", SettingsText(RgbdKeys())), SensorType::kRgbD);
  EXPECT_DOUBLE_EQ(s.camera.fx, 517.306408);
  EXPECT_DOUBLE_EQ(s.camera.cy, 255.313989);
  EXPECT_DOUBLE_EQ(s.camera.distortion.k2, -0.953104);
  EXPECT_DOUBLE_EQ(s.camera.distortion.k3, 1.163314);
  EXPECT_EQ(s.camera.width, 640);
  EXPECT_EQ(s.camera.height, 480);
  EXPECT_DOUBLE_EQ(s.fps, 30.0);
  EXPECT_TRUE(s.rgb);
  EXPECT_DOUBLE_EQ(s.bf, 40.0);
  EXPECT_DOUBLE_EQ(s.th_depth, 40.0);
  EXPECT_DOUBLE_EQ(s.depth_map_factor, 5000.0);
  EXPECT_EQ(s.orb.num_features, 1000);
  EXPECT_DOUBLE_EQ(s.Baseline(), 40.0 / 517.306408);
  EXPECT_DOUBLE_EQ(s.CloseDepthMetres(), 40.0 * 40.0 / 517.306408);
}

TEST(LoadOrbSlamSettings, OptionalKeysKeepDefaults) {
  testing::TempDir dir;
  Keys keys = Without(Without(Without(RgbdKeys(), "Camera.k3"), "Camera.width"), "Camera.height");
  keys = Without(Without(Without(keys, "Camera.bf"), "ThDepth"), "DepthMapFactor");
  const OrbSlamSettings s =
      LoadOrbSlamSettings(dir.Write("mono.yaml", SettingsText(keys)), SensorType::kMonocular);
  EXPECT_DOUBLE_EQ(s.camera.distortion.k3, 0.0);
  EXPECT_EQ(s.camera.width, 0);
  EXPECT_DOUBLE_EQ(s.bf, 0.0);
  EXPECT_DOUBLE_EQ(s.Baseline(), 0.0);
  EXPECT_DOUBLE_EQ(s.th_depth, 35.0);
}

TEST(LoadOrbSlamSettings, OrbSlam2SpellingsParse) {
  // ORB-SLAM2's files write "Viewer.PointSize:2" without a blank and "Camera.RGB: 0" for BGR.
  testing::TempDir dir;
  const std::string text = SettingsText(With(RgbdKeys(), "Camera.RGB", "0")) +
                           "Viewer.PointSize:2\nViewer.ViewpointF: 500 # comment\n";
  const OrbSlamSettings s = LoadOrbSlamSettings(dir.Write("s.yaml", text), SensorType::kRgbD);
  EXPECT_FALSE(s.rgb);
}

TEST(LoadOrbSlamSettings, RequiredKeysDependOnTheSensor) {
  testing::TempDir dir;
  const Keys mono = Without(Without(Without(RgbdKeys(), "Camera.bf"), "ThDepth"), "DepthMapFactor");
  const std::string path = dir.Write("mono.yaml", SettingsText(mono));
  EXPECT_NO_THROW(LoadOrbSlamSettings(path, SensorType::kMonocular));
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(path, SensorType::kStereo); }),
              AllOf(HasSubstr(path), HasSubstr("required key 'Camera.bf' is missing")));
  const std::string no_th = dir.Write("no_th.yaml", SettingsText(Without(RgbdKeys(), "ThDepth")));
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(no_th, SensorType::kStereo); }),
              AllOf(HasSubstr(no_th), HasSubstr("'ThDepth'")));
  const std::string stereo =
      dir.Write("stereo.yaml", SettingsText(Without(RgbdKeys(), "DepthMapFactor")));
  EXPECT_NO_THROW(LoadOrbSlamSettings(stereo, SensorType::kStereo));
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(stereo, SensorType::kRgbD); }),
              AllOf(HasSubstr(stereo), HasSubstr("'DepthMapFactor'")));
  // An RGB-D file serves a monocular run: its extra keys are known, read and checked.
  const std::string rgbd = dir.Write("rgbd.yaml", SettingsText(RgbdKeys()));
  EXPECT_DOUBLE_EQ(LoadOrbSlamSettings(rgbd, SensorType::kMonocular).bf, 40.0);
}

TEST(LoadOrbSlamSettings, EveryCommonKeyIsRequired) {
  testing::TempDir dir;
  for (const char* key :
       {"Camera.fx", "Camera.fy", "Camera.cx", "Camera.cy", "Camera.k1", "Camera.k2", "Camera.p1",
        "Camera.p2", "Camera.fps", "Camera.RGB", "ORBextractor.nFeatures",
        "ORBextractor.scaleFactor", "ORBextractor.nLevels", "ORBextractor.iniThFAST",
        "ORBextractor.minThFAST"}) {
    const std::string path = dir.Write("s.yaml", SettingsText(Without(RgbdKeys(), key)));
    EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(path, SensorType::kMonocular); }),
                AllOf(HasSubstr(path), HasSubstr(std::string("'") + key + "' is missing")));
  }
}

TEST(LoadOrbSlamSettings, UnknownKeyNamesKeyAndFile) {
  testing::TempDir dir;
  const std::string path =
      dir.Write("s.yaml", SettingsText(With(RgbdKeys(), "ORBextractor.nFeature", "1000")));
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(path, SensorType::kRgbD); }),
              AllOf(HasSubstr(path), HasSubstr("unknown key 'ORBextractor.nFeature'")));
}

TEST(LoadOrbSlamSettings, WrongTypesNameKeyAndFile) {
  testing::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"Camera.fx", "\"fast\""},         {"ORBextractor.nFeatures", "1000.5"},
      {"ORBextractor.nLevels", "eight"}, {"Camera.RGB", "2"},
      {"Camera.width", "640.5"},         {"ThDepth", "[1, 2]"},
  };
  for (const auto& [key, value] : cases) {
    const std::string path = dir.Write("s.yaml", SettingsText(With(RgbdKeys(), key, value)));
    EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(path, SensorType::kRgbD); }),
                AllOf(HasSubstr(path), HasSubstr("'" + key + "' must be")))
        << key << ": " << value;
  }
}

TEST(LoadOrbSlamSettings, InvalidValuesNameTheKeyAndFile) {
  testing::TempDir dir;
  struct Case {
    std::string key, value, message;
    SensorType sensor;
  };
  const std::vector<Case> cases = {
      {"Camera.fx", "-517.3", "fx", SensorType::kRgbD},
      {"Camera.cx", "700", "cx", SensorType::kRgbD},
      {"Camera.fps", "0", "Camera.fps", SensorType::kRgbD},
      {"Camera.bf", "0", "Camera.bf", SensorType::kStereo},
      {"Camera.bf", "-40", "Camera.bf", SensorType::kMonocular},
      {"ThDepth", "-1", "ThDepth", SensorType::kStereo},
      {"DepthMapFactor", "0", "DepthMapFactor", SensorType::kRgbD},
      {"ORBextractor.nFeatures", "0", "ORBextractor.nFeatures", SensorType::kRgbD},
      {"ORBextractor.scaleFactor", "1.0", "ORBextractor.scaleFactor", SensorType::kRgbD},
      {"ORBextractor.nLevels", "0", "ORBextractor.nLevels", SensorType::kRgbD},
      {"ORBextractor.iniThFAST", "300", "ORBextractor.iniThFAST", SensorType::kRgbD},
      {"ORBextractor.minThFAST", "25", "ORBextractor.minThFAST", SensorType::kRgbD},
      {"Camera.k1", ".nan", "k1", SensorType::kRgbD},
  };
  for (const Case& c : cases) {
    const std::string path = dir.Write("s.yaml", SettingsText(With(RgbdKeys(), c.key, c.value)));
    EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(path, c.sensor); }),
                AllOf(HasSubstr(path), HasSubstr(c.message)))
        << c.key << ": " << c.value;
  }
  const std::string half = dir.Write("s.yaml", SettingsText(Without(RgbdKeys(), "Camera.height")));
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(half, SensorType::kRgbD); }),
              AllOf(HasSubstr(half), HasSubstr("height")));
}

// Issue 31: values that passed the old checks and then aborted deep inside the system (an SE(3)
// check on inf/NaN poses, an empty keypoint grid) are refused here, naming the key and file.
TEST(LoadOrbSlamSettings, AbsurdCameraValuesNameTheKeyAndFile) {
  testing::TempDir dir;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"Camera.fx", "1e-300"},     {"Camera.fx", "1e300"},    {"Camera.fy", "1e300"},
      {"Camera.fy", "0.5"},        {"Camera.k1", "-1e6"},     {"Camera.k3", "1e300"},
      {"Camera.p1", "0.9"},        {"Camera.bf", "1e-9"},     {"Camera.bf", "1e9"},
      {"DepthMapFactor", "1e-30"}, {"DepthMapFactor", "1e9"},
  };
  for (const auto& [key, value] : cases) {
    const std::string path = dir.Write("s.yaml", SettingsText(With(RgbdKeys(), key, value)));
    EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(path, SensorType::kRgbD); }),
                AllOf(HasSubstr(path), HasSubstr(key)))
        << key << ": " << value;
  }
  // The file without the distortion passes: the refusals above are the values, not the file.
  Keys ideal = RgbdKeys();
  for (const char* k : {"Camera.k1", "Camera.k2", "Camera.p1", "Camera.p2", "Camera.k3"}) {
    ideal = With(ideal, k, "0.0");
  }
  EXPECT_NO_THROW(LoadOrbSlamSettings(dir.Write("s.yaml", SettingsText(ideal)), SensorType::kRgbD));
}

// Issue 31: without Camera.width/height the checks that need the size ran nowhere, and k1 = -1e6
// reached a CHECK in the keypoint grid; the first frame's size completes them.
TEST(CompleteImageSize, ChecksTheDistortionAgainstTheFirstFramesSize) {
  testing::TempDir dir;
  const Keys unsized = Without(Without(RgbdKeys(), "Camera.width"), "Camera.height");
  const std::string bad = dir.Write("bad.yaml", SettingsText(With(unsized, "Camera.k1", "-1e6")));
  OrbSlamSettings settings = LoadOrbSlamSettings(bad, SensorType::kRgbD);  // no size: accepted
  EXPECT_FALSE(settings.camera.HasSize());
  EXPECT_THAT(
      ErrorOf([&] { CompleteImageSize(&settings, bad, 640, 480, "rgb/0.png"); }),
      AllOf(HasSubstr(bad), HasSubstr("Camera.k1"), HasSubstr("640x480"), HasSubstr("rgb/0.png")));
  // A principal point outside the first frame is named too.
  const std::string tiny = dir.Write("tiny.yaml", SettingsText(unsized));
  settings = LoadOrbSlamSettings(tiny, SensorType::kRgbD);
  EXPECT_THAT(ErrorOf([&] { CompleteImageSize(&settings, tiny, 200, 100, "rgb/0.png"); }),
              AllOf(HasSubstr(tiny), HasSubstr("Camera.cx")));
  // Good settings take the size; settings that give one keep it.
  const std::string good = dir.Write("good.yaml", SettingsText(unsized));
  settings = LoadOrbSlamSettings(good, SensorType::kRgbD);
  CompleteImageSize(&settings, good, 640, 480, "rgb/0.png");
  EXPECT_EQ(settings.camera.width, 640);
  EXPECT_EQ(settings.camera.height, 480);
  settings =
      LoadOrbSlamSettings(dir.Write("sized.yaml", SettingsText(RgbdKeys())), SensorType::kRgbD);
  CompleteImageSize(&settings, "sized.yaml", 320, 240, "rgb/0.png");
  EXPECT_EQ(settings.camera.width, 640);
}

TEST(LoadOrbSlamSettings, NumbersMustBeDecimal) {
  // OpenCV reads 0x217 as 535 and 030 as 24 (strtol with base 0); a settings file means neither.
  testing::TempDir dir;
  for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{
           {"Camera.fx", "0x217"}, {"Camera.fps", "030"}, {"ORBextractor.nLevels", "-010"}}) {
    const std::string path = dir.Write("s.yaml", SettingsText(With(RgbdKeys(), key, value)));
    EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(path, SensorType::kRgbD); }),
                AllOf(HasSubstr(path + ":"), HasSubstr(key), HasSubstr("decimal")))
        << key << ": " << value;
  }
  // Decimal numbers with a leading zero before the point, and exponents, stay numbers.
  const std::string fine = dir.Write(
      "s.yaml", SettingsText(With(With(RgbdKeys(), "Camera.p1", "0.0"), "Camera.fps", "3e1")));
  EXPECT_NO_THROW(LoadOrbSlamSettings(fine, SensorType::kRgbD));
}

TEST(LoadOrbSlamSettings, ADirectoryOrAListIsNotASettingsFile) {
  testing::TempDir dir;
  dir.Write("folder/x", "");  // creates the folder
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(dir.path() + "/folder", SensorType::kRgbD); }),
              AllOf(HasSubstr(dir.path() + "/folder"), HasSubstr("is a directory")));
  const std::string list = dir.Write("list.yaml", "%YAML:1.0\n- Camera.fx: 500\n- 2\n");
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(list, SensorType::kRgbD); }),
              AllOf(HasSubstr(list), HasSubstr("top level")));
}

TEST(LoadOrbSlamSettings, MissingOrBrokenFile) {
  testing::TempDir dir;
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(dir.path() + "/none.yaml", SensorType::kRgbD); }),
              AllOf(HasSubstr("none.yaml"), HasSubstr("not found")));
  const std::string broken = dir.Write("broken.yaml", "%YAML:1.0\nCamera.fx: [1, 2\n");
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(broken, SensorType::kRgbD); }), HasSubstr(broken));
}

// The twelve rectification keys of ORB-SLAM2's Stereo/EuRoC.yaml (no space after "data:" in
// LEFT.D, as there).
std::string RectificationText(const std::string& left_p_fx = "435.2046959714599") {
  const auto matrix = [](const std::string& name, int rows, int cols, const std::string& data) {
    return fmt::format("{}: !!opencv-matrix\n   rows: {}\n   cols: {}\n   dt: d\n   data:{}\n",
                       name, rows, cols, data);
  };
  const std::string r = "[1, 0, 0, 0, 1, 0, 0, 0, 1]";
  return "LEFT.height: 480\nLEFT.width: 752\n" +
         matrix("LEFT.D", 1, 5, "[-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0.0]") +
         matrix("LEFT.K", 3, 3, "[458.654, 0.0, 367.215, 0.0, 457.296, 248.375, 0.0, 0.0, 1.0]") +
         matrix("LEFT.R", 3, 3, r) +
         matrix("LEFT.P", 3, 4,
                "[" + left_p_fx +
                    ", 0, 367.4517211914062, 0, 0, 435.2046959714599, 252.2008514404297, 0, 0, "
                    "0, 1, 0]") +
         "RIGHT.height: 480\nRIGHT.width: 752\n" +
         matrix("RIGHT.D", 1, 5, "[-0.28368365, 0.07451284, -0.00010473, -3.555907e-05, 0.0]") +
         matrix("RIGHT.K", 3, 3, "[457.587, 0.0, 379.999, 0.0, 456.134, 255.238, 0.0, 0.0, 1]") +
         matrix("RIGHT.R", 3, 3, r) +
         matrix("RIGHT.P", 3, 4,
                "[435.2046959714599, 0, 367.4517211914062, -47.90639384423901, 0, "
                "435.2046959714599, 252.2008514404297, 0, 0, 0, 1, 0]");
}

Keys EurocStereoKeys() {
  Keys keys = Without(RgbdKeys(), "DepthMapFactor");
  keys = With(keys, "Camera.fx", "435.2046959714599");
  keys = With(keys, "Camera.fy", "435.2046959714599");
  keys = With(keys, "Camera.cx", "367.4517211914062");
  keys = With(keys, "Camera.cy", "252.2008514404297");
  keys = With(keys, "Camera.width", "752");
  keys = With(keys, "Camera.bf", "47.90639384423901");
  for (const char* k : {"Camera.k1", "Camera.k2", "Camera.p1", "Camera.p2", "Camera.k3"}) {
    keys = With(keys, k, "0.0");
  }
  return keys;
}

TEST(LoadOrbSlamSettings, ReadsStereoRectification) {
  testing::TempDir dir;
  const std::string path =
      dir.Write("euroc.yaml", SettingsText(EurocStereoKeys()) + RectificationText());
  const OrbSlamSettings s = LoadOrbSlamSettings(path, SensorType::kStereo);
  ASSERT_TRUE(s.rectification.has_value());
  const StereoRectification& r = *s.rectification;
  EXPECT_EQ(r.left.width, 752);
  EXPECT_EQ(r.right.height, 480);
  ASSERT_EQ(r.left.D.size(), 5u);
  EXPECT_DOUBLE_EQ(r.left.D[0], -0.28340811);
  EXPECT_DOUBLE_EQ(r.left.K(0, 2), 367.215);  // row-major
  EXPECT_DOUBLE_EQ(r.left.K(1, 1), 457.296);
  EXPECT_TRUE(r.left.R.isIdentity());
  EXPECT_DOUBLE_EQ(r.right.P(0, 3), -47.90639384423901);
  EXPECT_DOUBLE_EQ(r.right.K(1, 2), 255.238);
}

TEST(LoadOrbSlamSettings, BadRectificationNamesTheKey) {
  testing::TempDir dir;
  const std::string base = SettingsText(EurocStereoKeys());
  // Only the left half: the right keys are then required.
  const std::string text = RectificationText();
  const std::string left_only = text.substr(0, text.find("RIGHT.height"));
  const std::string a = dir.Write("a.yaml", base + left_only);
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(a, SensorType::kStereo); }),
              AllOf(HasSubstr(a), HasSubstr("'RIGHT.")));
  // LEFT.P with 9 values.
  std::string short_p = text;
  const size_t p = short_p.find("LEFT.P");
  const size_t data = short_p.find("data:", p);
  short_p.replace(data, short_p.find('\n', data) - data, "data:[1, 0, 0, 0, 1, 0, 0, 0, 1]");
  const std::string b = dir.Write("b.yaml", base + short_p);
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(b, SensorType::kStereo); }),
              AllOf(HasSubstr(b), HasSubstr("'LEFT.P' must be a 3x4 matrix")));
  // LEFT.P disagreeing with Camera.fx.
  const std::string c = dir.Write("c.yaml", base + RectificationText("400.0"));
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(c, SensorType::kStereo); }),
              AllOf(HasSubstr(c), HasSubstr("LEFT.P intrinsics")));
  // Camera.bf disagreeing with RIGHT.P.
  const std::string d =
      dir.Write("d.yaml", SettingsText(With(EurocStereoKeys(), "Camera.bf", "40")) + text);
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(d, SensorType::kStereo); }),
              AllOf(HasSubstr(d), HasSubstr("RIGHT.P(0,3)")));
  // A non-rotation R.
  std::string bad_r = text;
  bad_r.replace(bad_r.find("[1, 0, 0, 0, 1, 0, 0, 0, 1]"), 27, "[2, 0, 0, 0, 1, 0, 0, 0, 1]");
  const std::string e = dir.Write("e.yaml", base + bad_r);
  EXPECT_THAT(ErrorOf([&] { LoadOrbSlamSettings(e, SensorType::kStereo); }),
              AllOf(HasSubstr(e), HasSubstr("LEFT.R is not a rotation")));
}

// The settings shipped in configs/ (tests run from the repository root).
TEST(ShippedConfigs, TumRgbdFilesLoad) {
  const OrbSlamSettings tum1 = LoadOrbSlamSettings("configs/TUM1.yaml", SensorType::kRgbD);
  EXPECT_DOUBLE_EQ(tum1.camera.fx, 517.306408);
  EXPECT_DOUBLE_EQ(tum1.camera.distortion.k3, 1.163314);
  const OrbSlamSettings tum2 = LoadOrbSlamSettings("configs/TUM2.yaml", SensorType::kRgbD);
  EXPECT_DOUBLE_EQ(tum2.camera.fx, 520.908620);
  EXPECT_DOUBLE_EQ(tum2.depth_map_factor, 5208.0);
  const OrbSlamSettings tum3 = LoadOrbSlamSettings("configs/TUM3.yaml", SensorType::kRgbD);
  EXPECT_DOUBLE_EQ(tum3.camera.fx, 535.4);
  EXPECT_DOUBLE_EQ(tum3.camera.fy, 539.2);
  EXPECT_DOUBLE_EQ(tum3.camera.cx, 320.1);
  EXPECT_DOUBLE_EQ(tum3.camera.cy, 247.6);
  EXPECT_TRUE(tum3.camera.distortion.IsZero());
  EXPECT_DOUBLE_EQ(tum3.bf, 40.0);
  EXPECT_DOUBLE_EQ(tum3.th_depth, 40.0);
  EXPECT_DOUBLE_EQ(tum3.depth_map_factor, 5000.0);
  EXPECT_EQ(tum3.orb.num_features, 1000);
  for (const char* name : {"configs/TUM1.yaml", "configs/TUM2.yaml", "configs/TUM3.yaml"}) {
    EXPECT_NO_THROW(LoadOrbSlamSettings(name, SensorType::kMonocular)) << name;
  }
}

TEST(ShippedConfigs, KittiFilesLoad) {
  const OrbSlamSettings stereo =
      LoadOrbSlamSettings("configs/KITTI04-12.yaml", SensorType::kStereo);
  EXPECT_DOUBLE_EQ(stereo.camera.fx, 707.0912);
  EXPECT_DOUBLE_EQ(stereo.camera.fy, 707.0912);
  EXPECT_DOUBLE_EQ(stereo.camera.cx, 601.8873);
  EXPECT_DOUBLE_EQ(stereo.camera.cy, 183.1104);
  EXPECT_DOUBLE_EQ(stereo.bf, 379.8145);
  EXPECT_NEAR(stereo.Baseline(), 0.53715, 1e-4);
  EXPECT_DOUBLE_EQ(stereo.th_depth, 35.0);
  EXPECT_NEAR(stereo.CloseDepthMetres(), 35.0 * 0.53715, 1e-2);
  EXPECT_EQ(stereo.orb.num_features, 2000);
  EXPECT_DOUBLE_EQ(stereo.fps, 10.0);
  const OrbSlamSettings mono =
      LoadOrbSlamSettings("configs/KITTI04-12_mono.yaml", SensorType::kMonocular);
  EXPECT_DOUBLE_EQ(mono.camera.fx, 707.0912);
  EXPECT_DOUBLE_EQ(mono.bf, 0.0);
  EXPECT_EQ(mono.orb.num_features, 2000);
  EXPECT_THROW(LoadOrbSlamSettings("configs/KITTI04-12_mono.yaml", SensorType::kStereo),
               InputError);
}

TEST(ShippedConfigs, EurocStereoWithRectificationLoads) {
  const OrbSlamSettings s = LoadOrbSlamSettings("configs/EuRoC.yaml", SensorType::kStereo);
  ASSERT_TRUE(s.rectification.has_value());
  EXPECT_NEAR(s.Baseline(), 0.110, 1e-3);
  EXPECT_EQ(s.orb.num_features, 1200);
  EXPECT_DOUBLE_EQ(s.rectification->right.R(2, 2), 0.999945173484644);
}

}  // namespace
}  // namespace moslam::io
