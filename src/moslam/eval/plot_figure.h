// A tiny vector-drawing abstraction for the trajectory plot: the layout code (plot.cc) records
// shapes in pixel coordinates into a Figure, and two backends turn the same Figure into a raster
// image (OpenCV, antialiased) or an SVG document. Sharing the display list keeps both outputs
// identical in content; only glyph shapes differ (Hershey font vs the viewer's sans-serif).
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include <opencv2/core.hpp>

namespace moslam::eval::internal {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};

struct PolylineShape {
  std::vector<cv::Point2d> points;  // pixels, y down
  Rgb color;
  double width = 1.0;  // pixels
  bool dashed = false;
};

struct RectShape {
  cv::Rect2d rect;
  Rgb fill;
  bool filled = true;  // false: outline of `width` pixels in `fill` colour
  double width = 1.0;
};

struct CircleShape {
  cv::Point2d center;
  double radius = 3.0;
  Rgb fill;
};

enum class Anchor { kStart, kMiddle, kEnd };  // horizontal, along the text direction

struct TextShape {
  std::string text;
  cv::Point2d baseline;  // point on the baseline selected by `anchor`
  double size = 16.0;    // font size (em) in pixels
  Rgb color;
  Anchor anchor = Anchor::kStart;
  bool bold = false;
  bool vertical = false;  // rotated 90 degrees counter-clockwise (reads bottom to top)
};

using Shape = std::variant<PolylineShape, RectShape, CircleShape, TextShape>;

struct Figure {
  int width = 1600;
  int height = 1000;
  std::vector<Shape> shapes;  // painted in order, over a white background

  void Add(Shape shape) { shapes.push_back(std::move(shape)); }
};

// Height of capital letters relative to the font size, for vertical centring of text. 0.72 is
// typical of sans-serif faces (DejaVu Sans, Arial); the raster backend scales its font to match.
constexpr double kCapHeight = 0.72;

// Advance width in pixels of `text` as the raster backend draws it; typical sans-serif faces in
// SVG viewers are a little narrower, so layout that reserves this much space fits both.
double TextWidth(const std::string& text, double size, bool bold = false);

// 8-bit BGR image of figure.width x figure.height.
cv::Mat RenderRaster(const Figure& figure);
// A complete, standalone SVG 1.1 document.
std::string RenderSvg(const Figure& figure);

}  // namespace moslam::eval::internal
