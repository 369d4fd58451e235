#include "moslam/eval/plot.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "moslam/eval/plot_axes.h"
#include "moslam/eval/plot_layout.h"
#include "moslam/eval/plot_scale.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam::eval {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A circle of radius 2 m in the x-y plane; the estimate drifts outwards and upwards over time.
TrajectoryPlotData CircleWithDrift(int n) {
  TrajectoryPlotData data;
  data.title = "ATE, SE(3)-aligned: circle & drift <test>";
  data.error_label = "ATE [m]";
  for (int i = 0; i < n; ++i) {
    const double t = 0.05 * i;
    const double angle = 2.0 * M_PI * i / std::max(1, n - 1);
    const Eigen::Vector3d ref(2.0 * std::cos(angle), 2.0 * std::sin(angle), 0.3 * std::sin(angle));
    const double drift = 0.1 * i / std::max(1, n - 1);
    const Eigen::Vector3d est = ref + Eigen::Vector3d(drift, 0.5 * drift, 0.02 * std::sin(7 * t));
    data.times.push_back(t);
    data.reference.push_back(ref);
    data.estimate.push_back(est);
    data.errors.push_back((est - ref).norm());
  }
  return data;
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// Number of pixels within `tolerance` (per channel) of an RGB colour.
int CountColour(const cv::Mat& bgr, internal::Rgb c, int tolerance = 12) {
  cv::Mat mask;
  cv::inRange(bgr, cv::Scalar(c.b - tolerance, c.g - tolerance, c.r - tolerance),
              cv::Scalar(c.b + tolerance, c.g + tolerance, c.r + tolerance), mask);
  return cv::countNonZero(mask);
}

// Checks that tags nest properly: enough to catch unclosed or misordered elements.
bool TagsBalanced(const std::string& xml) {
  std::vector<std::string> open;
  for (size_t pos = xml.find('<'); pos != std::string::npos; pos = xml.find('<', pos + 1)) {
    const size_t end = xml.find('>', pos);
    if (end == std::string::npos) return false;
    const std::string tag = xml.substr(pos + 1, end - pos - 1);
    if (tag.empty() || tag[0] == '?' || tag[0] == '!' || tag.back() == '/') continue;
    const std::string name = tag.substr(tag[0] == '/', tag.find_first_of(" \n") - (tag[0] == '/'));
    if (tag[0] != '/') {
      open.push_back(name);
    } else if (open.empty() || open.back() != name) {
      return false;
    } else {
      open.pop_back();
    }
  }
  return open.empty();
}

TEST(TrajectoryPlot, WritesPngWithBothLineColours) {
  testing::TempDir dir;
  const std::string path = dir.path() + "/plot.png";
  WriteTrajectoryPlot(CircleWithDrift(500), path);
  const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(image.cols, 1600);
  EXPECT_EQ(image.rows, 1000);
  EXPECT_GT(CountColour(image, internal::kReference), 500);
  EXPECT_GT(CountColour(image, internal::kEstimate), 500);
  EXPECT_GT(CountColour(image, internal::kError), 200);
  // The top view is coloured by error: both ends of the colour map appear.
  EXPECT_GT(CountColour(image, internal::Plasma(0.0)), 50);
  EXPECT_GT(CountColour(image, internal::Plasma(1.0)), 50);
}

TEST(TrajectoryPlot, WritesSvgWithPolylinesAndEscapedTitle) {
  testing::TempDir dir;
  const std::string path = dir.path() + "/plot.SVG";  // the extension is case-insensitive
  WriteTrajectoryPlot(CircleWithDrift(500), path);
  const std::string svg = ReadAll(path);
  EXPECT_TRUE(StartsWith(svg, "<?xml version=\"1.0\""));
  EXPECT_THAT(svg, HasSubstr("<svg xmlns=\"http://www.w3.org/2000/svg\""));
  EXPECT_THAT(svg, HasSubstr("<polyline "));
  EXPECT_THAT(svg, HasSubstr("ATE, SE(3)-aligned: circle &amp; drift &lt;test&gt;"));
  EXPECT_THAT(svg, HasSubstr(">ATE [m]</text>"));
  EXPECT_THAT(svg, HasSubstr(">time since start [s]</text>"));
  EXPECT_TRUE(EndsWith(svg, "</svg>\n"));
  EXPECT_TRUE(TagsBalanced(svg));
}

TEST(TrajectoryPlot, RejectsUnknownExtension) {
  testing::TempDir dir;
  EXPECT_THROW(WriteTrajectoryPlot(CircleWithDrift(10), dir.path() + "/plot.jpg"), InputError);
  EXPECT_THROW(WriteTrajectoryPlot(CircleWithDrift(10), dir.path() + "/png"), InputError);
}

TEST(TrajectoryPlot, RejectsInconsistentLengths) {
  testing::TempDir dir;
  const std::string path = dir.path() + "/plot.png";
  TrajectoryPlotData data = CircleWithDrift(10);
  data.estimate.pop_back();
  try {
    WriteTrajectoryPlot(data, path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("10 times, 10 reference and 9 estimate"));
  }
  data = CircleWithDrift(10);
  data.errors.push_back(0.0);
  EXPECT_THROW(WriteTrajectoryPlot(data, path), InputError);
  data = CircleWithDrift(10);
  data.times.pop_back();
  EXPECT_THROW(WriteTrajectoryPlot(data, path), InputError);
}

TEST(TrajectoryPlot, RejectsEmptyData) {
  testing::TempDir dir;
  TrajectoryPlotData data;
  data.title = "empty";
  EXPECT_THROW(WriteTrajectoryPlot(data, dir.path() + "/plot.png"), InputError);
  EXPECT_THROW(WriteTrajectoryPlot(data, dir.path() + "/plot.svg"), InputError);
}

TEST(TrajectoryPlot, UnwritablePathThrows) {
  EXPECT_THROW(WriteTrajectoryPlot(CircleWithDrift(10), "/nonexistent/dir/plot.png"), InputError);
  EXPECT_THROW(WriteTrajectoryPlot(CircleWithDrift(10), "/nonexistent/dir/plot.svg"), InputError);
}

TEST(TrajectoryPlot, SkipsNaNValues) {
  testing::TempDir dir;
  TrajectoryPlotData data = CircleWithDrift(200);
  data.reference[5].x() = kNaN;
  data.estimate[50] = Eigen::Vector3d::Constant(kNaN);
  data.times[0] = kNaN;
  data.times[100] = std::numeric_limits<double>::infinity();
  data.errors[7] = kNaN;
  for (const char* name : {"/nan.png", "/nan.svg"}) {
    WriteTrajectoryPlot(data, dir.path() + name);
    EXPECT_FALSE(ReadAll(dir.path() + name).empty());
  }
  EXPECT_EQ(cv::imread(dir.path() + "/nan.png").cols, 1600);
  EXPECT_THAT(ReadAll(dir.path() + "/nan.svg"), ::testing::Not(HasSubstr("nan")));

  // Nothing finite at all still gives a (mostly empty) figure.
  for (auto& p : data.reference) p.setConstant(kNaN);
  for (auto& p : data.estimate) p.setConstant(kNaN);
  for (double& t : data.times) t = kNaN;
  for (double& e : data.errors) e = kNaN;
  EXPECT_NO_THROW(WriteTrajectoryPlot(data, dir.path() + "/allnan.png"));
  EXPECT_NO_THROW(WriteTrajectoryPlot(data, dir.path() + "/allnan.svg"));
  EXPECT_THAT(ReadAll(dir.path() + "/allnan.svg"), HasSubstr(">no error values</text>"));
}

TEST(TrajectoryPlot, SinglePoseAndConstantCoordinates) {
  testing::TempDir dir;
  TrajectoryPlotData one = CircleWithDrift(1);
  WriteTrajectoryPlot(one, dir.path() + "/one.png");
  EXPECT_GT(CountColour(cv::imread(dir.path() + "/one.png"), internal::kEstimate), 10);

  TrajectoryPlotData flat = CircleWithDrift(100);
  for (auto& p : flat.reference) p.z() = 1.5;
  for (auto& p : flat.estimate) p.z() = 1.5;
  for (double& e : flat.errors) e = 0.0;
  WriteTrajectoryPlot(flat, dir.path() + "/flat.svg");
  const std::string svg = ReadAll(dir.path() + "/flat.svg");
  EXPECT_THAT(svg, HasSubstr(">1.5</text>"));  // z axis padded around the constant value
  EXPECT_THAT(svg, ::testing::Not(HasSubstr("inf")));
}

TEST(TrajectoryPlot, ShorterErrorsArePlottedWithoutColouring) {
  testing::TempDir dir;
  TrajectoryPlotData data = CircleWithDrift(300);
  data.errors.resize(250);
  data.error_label = "RPE trans. [m]";
  WriteTrajectoryPlot(data, dir.path() + "/rpe.png");
  const cv::Mat image = cv::imread(dir.path() + "/rpe.png");
  EXPECT_GT(CountColour(image, internal::kError), 200);
  EXPECT_LT(CountColour(image, internal::Plasma(1.0)), 5);  // no colour bar, plain estimate
}

TEST(TrajectoryPlot, TopViewUsesTheTwoLargestAxes) {
  TrajectoryPlotData data = CircleWithDrift(100);
  for (auto& p : data.reference) p = Eigen::Vector3d(p.x(), 0.01 * p.z(), p.y());
  data.estimate = data.reference;
  const internal::Figure figure = internal::LayoutTrajectoryPlot(data);
  bool found = false;
  for (const auto& shape : figure.shapes) {
    if (const auto* text = std::get_if<internal::TextShape>(&shape)) {
      found = found || StartsWith(text->text, "Top view (x-z)");
    }
  }
  EXPECT_TRUE(found);
}

TEST(TrajectoryPlot, RendersTumGroundTruth) {
  MOSLAM_SHARED_OR_SKIP(path, "data/trajectories/fr2_desk_groundtruth.txt");
  TrajectoryPlotData data;
  data.title = "fr2_desk ground truth against itself, shifted";
  data.error_label = "ATE [m]";
  for (const auto& line : ReadDataLines(path)) {
    const auto fields = SplitFields(line.text);
    ASSERT_EQ(fields.size(), 8u) << line.number;
    data.times.push_back(*ParseDouble(fields[0]));
    const Eigen::Vector3d p(*ParseDouble(fields[1]), *ParseDouble(fields[2]),
                            *ParseDouble(fields[3]));
    data.reference.push_back(p);
    data.estimate.push_back(p + Eigen::Vector3d(0.01, 0.0, 0.0));
    data.errors.push_back(0.01);
  }
  ASSERT_GT(data.times.size(), 20000u);
  testing::TempDir dir;
  WriteTrajectoryPlot(data, dir.path() + "/fr2.png");
  const cv::Mat image = cv::imread(dir.path() + "/fr2.png");
  EXPECT_GT(CountColour(image, internal::kReference), 1000);
  EXPECT_GT(CountColour(image, internal::kEstimate), 1000);
}

TEST(TrajectoryPlot, LongTimeGapsBreakTheLines) {
  TrajectoryPlotData data = CircleWithDrift(200);
  auto polylines = [](const TrajectoryPlotData& d) {
    int count = 0;
    for (const auto& shape : internal::LayoutTrajectoryPlot(d).shapes) {
      const auto* line = std::get_if<internal::PolylineShape>(&shape);
      count += line != nullptr && line->points.size() > 20;  // data lines, not grid or ticks
    }
    return count;
  };
  const int without_gap = polylines(data);
  for (size_t i = 100; i < data.times.size(); ++i) data.times[i] += 30.0;  // tracking lost
  EXPECT_GT(polylines(data), without_gap);
}

TEST(TrajectoryPlot, SvgHoldsEveryLineOfTheFigure) {
  const TrajectoryPlotData data = CircleWithDrift(300);
  int lines = 0;
  for (const auto& shape : internal::LayoutTrajectoryPlot(data).shapes) {
    const auto* line = std::get_if<internal::PolylineShape>(&shape);
    lines += line != nullptr && line->points.size() >= 2;
  }
  testing::TempDir dir;
  WriteTrajectoryPlot(data, dir.path() + "/plot.svg");
  const std::string svg = ReadAll(dir.path() + "/plot.svg");
  int svg_lines = 0;
  for (size_t pos = svg.find("<polyline "); pos != std::string::npos;
       pos = svg.find("<polyline ", pos + 1)) {
    ++svg_lines;
  }
  EXPECT_GT(lines, 20);
  EXPECT_EQ(svg_lines, lines);
}

TEST(PlotScale, NiceTicksFollowHeckbert) {
  const internal::Ticks ticks = internal::NiceTicks({0.0, 1.0}, 5);
  EXPECT_DOUBLE_EQ(ticks.step, 0.2);
  ASSERT_EQ(ticks.values.size(), 6u);
  EXPECT_NEAR(ticks.values.back(), 1.0, 1e-12);
  EXPECT_EQ(internal::NiceTicks({-3.7, 12.2}, 5).step, 5.0);
  EXPECT_THAT(internal::NiceTicks({-3.7, 12.2}, 5).values, ElementsAre(0.0, 5.0, 10.0));
  EXPECT_TRUE(internal::NiceTicks({1.0, 1.0}, 5).values.empty());
}

TEST(PlotScale, FormatsTicksAndValues) {
  EXPECT_EQ(internal::FormatTick(0.6000000000000001, 0.2), "0.6");
  EXPECT_EQ(internal::FormatTick(-1e-17, 0.2), "0.0");
  EXPECT_EQ(internal::FormatTick(250.0, 50.0), "250");
  EXPECT_EQ(internal::FormatTick(0.025, 0.005), "0.025");
  EXPECT_EQ(internal::FormatValue(0.0081442), "0.00814");
  EXPECT_EQ(internal::FormatValue(12.345), "12.3");
}

TEST(PlotScale, PadsZeroRanges) {
  const internal::Range r = internal::Padded({1.5, 1.5}, 0.1);
  EXPECT_DOUBLE_EQ(r.lo, 1.0);
  EXPECT_DOUBLE_EQ(r.hi, 2.0);
  const internal::Range s = internal::Padded({0.0, 2.0}, 0.1);
  EXPECT_DOUBLE_EQ(s.lo, -0.2);
  EXPECT_DOUBLE_EQ(s.hi, 2.2);
}

TEST(PlotScale, DecimationDropsSubpixelStepsAndBreaksAtNaN) {
  std::vector<cv::Point2d> pixels;
  for (int i = 0; i <= 100; ++i) pixels.emplace_back(0.1 * i, 0.0);  // 10 px in 0.1 px steps
  pixels.emplace_back(kNaN, 0.0);
  pixels.emplace_back(50.0, 50.0);
  const auto runs = internal::DecimatedRuns(pixels, 1.0);
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0].front(), 0u);
  EXPECT_EQ(runs[0].back(), 100u);  // the end of a run is always kept
  EXPECT_LE(runs[0].size(), 12u);
  EXPECT_THAT(runs[1], ElementsAre(102u));
}

}  // namespace
}  // namespace moslam::eval
