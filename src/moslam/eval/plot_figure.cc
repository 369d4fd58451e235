#include "moslam/eval/plot_figure.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

namespace moslam::eval::internal {
namespace {

// Dash pattern of dashed lines in pixels, the same in both backends.
constexpr double kDashOn = 9.0;
constexpr double kDashOff = 6.0;
// OpenCV draws with sub-pixel precision when coordinates carry `kShift` fractional bits.
constexpr int kShift = 4;
constexpr double kShiftScale = 1 << kShift;

// A polyline of one point is drawn as a dot a little wider than the line would be.
double DotRadius(const PolylineShape& line) { return line.width + 1.0; }

// ------------------------------------------------------------------------------------------------
// Raster backend (OpenCV).

cv::Scalar Bgr(const Rgb& c) { return cv::Scalar(c.b, c.g, c.r); }

// Figure coordinates follow SVG: pixel (i, j) covers [i, i+1] x [j, j+1]. OpenCV puts pixel
// centres at integers, hence the half-pixel shift.
cv::Point Fixed(const cv::Point2d& p) {
  return {static_cast<int>(std::lround((p.x - 0.5) * kShiftScale)),
          static_cast<int>(std::lround((p.y - 0.5) * kShiftScale))};
}

int Thickness(double width) { return std::max(1, static_cast<int>(std::lround(width))); }

// Splits a polyline into its visible dashes.
std::vector<std::vector<cv::Point2d>> Dashes(const std::vector<cv::Point2d>& points) {
  std::vector<std::vector<cv::Point2d>> dashes;
  std::vector<cv::Point2d> current{points.front()};
  bool on = true;
  double left = kDashOn;  // length left in the current dash or gap
  for (size_t i = 1; i < points.size(); ++i) {
    cv::Point2d a = points[i - 1];
    const cv::Point2d b = points[i];
    double length = std::hypot(b.x - a.x, b.y - a.y);
    while (length > left) {
      const cv::Point2d cut = a + (b - a) * (left / length);
      if (on) {
        current.push_back(cut);
        dashes.push_back(std::move(current));
        current.clear();
      } else {
        current = {cut};
      }
      length -= left;
      a = cut;
      on = !on;
      left = on ? kDashOn : kDashOff;
    }
    left -= length;
    if (on) current.push_back(b);
  }
  if (on && current.size() >= 2) dashes.push_back(std::move(current));
  return dashes;
}

void DrawPolyline(cv::Mat& image, const PolylineShape& line) {
  if (line.points.empty()) return;
  if (line.points.size() == 1) {
    cv::circle(image, Fixed(line.points[0]),
               static_cast<int>(std::lround(DotRadius(line) * kShiftScale)), Bgr(line.color),
               cv::FILLED, cv::LINE_AA, kShift);
    return;
  }
  std::vector<std::vector<cv::Point>> pieces;
  if (line.dashed) {
    for (const auto& dash : Dashes(line.points)) {
      pieces.emplace_back();
      for (const auto& p : dash) pieces.back().push_back(Fixed(p));
    }
  } else {
    pieces.emplace_back();
    for (const auto& p : line.points) pieces.back().push_back(Fixed(p));
  }
  cv::polylines(image, pieces, false, Bgr(line.color), Thickness(line.width), cv::LINE_AA, kShift);
}

void DrawRect(cv::Mat& image, const RectShape& shape) {
  // Integer corners and no antialiasing keep frames and bars crisp.
  const cv::Point a(static_cast<int>(std::lround(shape.rect.x)),
                    static_cast<int>(std::lround(shape.rect.y)));
  const cv::Point b(static_cast<int>(std::lround(shape.rect.x + shape.rect.width)) - 1,
                    static_cast<int>(std::lround(shape.rect.y + shape.rect.height)) - 1);
  cv::rectangle(image, a, b, Bgr(shape.fill), shape.filled ? cv::FILLED : Thickness(shape.width),
                cv::LINE_8);
}

// Hershey fonts have ASCII glyphs only: each other UTF-8 character becomes '?'.
std::string AsciiOnly(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x80) {
      out += c;
    } else if (u >= 0xC0) {  // lead byte; continuation bytes (0x80..0xBF) are dropped
      out += '?';
    }
  }
  return out;
}

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

// Hershey font scale whose capitals are kCapHeight * size tall.
double FontScale(double size) {
  int baseline = 0;
  static const double cap_at_unit = cv::getTextSize("X", kFont, 1.0, 1, &baseline).height;
  return kCapHeight * size / cap_at_unit;
}

void DrawText(cv::Mat& image, const TextShape& shape) {
  const int font = kFont;
  int baseline = 0;
  const double scale = FontScale(shape.size);
  const int thickness = shape.bold ? 2 : 1;
  const std::string text = AsciiOnly(shape.text);
  const cv::Size size = cv::getTextSize(text, font, scale, thickness, &baseline);
  const double shift = shape.anchor == Anchor::kStart    ? 0.0
                       : shape.anchor == Anchor::kMiddle ? size.width / 2.0
                                                         : static_cast<double>(size.width);
  if (!shape.vertical) {
    const cv::Point origin(static_cast<int>(std::lround(shape.baseline.x - shift)),
                           static_cast<int>(std::lround(shape.baseline.y)));
    cv::putText(image, text, origin, font, scale, Bgr(shape.color), thickness, cv::LINE_AA);
    return;
  }
  // OpenCV cannot rotate text: draw it as a coverage mask, rotate the mask and blend the colour.
  const int pad = 2 + thickness;
  cv::Mat mask(size.height + baseline + 2 * pad, size.width + 2 * pad, CV_8UC1, cv::Scalar(0));
  cv::putText(mask, text, cv::Point(pad, pad + size.height), font, scale, cv::Scalar(255),
              thickness, cv::LINE_AA);
  cv::rotate(mask, mask, cv::ROTATE_90_COUNTERCLOCKWISE);
  // After rotation the baseline runs vertically at column (pad + size.height) and the text
  // starts at row (rows - pad), going up.
  const int left = static_cast<int>(std::lround(shape.baseline.x)) - (pad + size.height);
  const int top = static_cast<int>(std::lround(shape.baseline.y + shift)) - (mask.rows - pad);
  const cv::Rect target =
      cv::Rect(left, top, mask.cols, mask.rows) & cv::Rect(0, 0, image.cols, image.rows);
  const cv::Vec3d color(shape.color.b, shape.color.g, shape.color.r);
  for (int y = target.y; y < target.y + target.height; ++y) {
    for (int x = target.x; x < target.x + target.width; ++x) {
      const double alpha = mask.at<std::uint8_t>(y - top, x - left) / 255.0;
      if (alpha == 0.0) continue;
      cv::Vec3b& pixel = image.at<cv::Vec3b>(y, x);
      for (int k = 0; k < 3; ++k) {
        pixel[k] = cv::saturate_cast<std::uint8_t>((1.0 - alpha) * pixel[k] + alpha * color[k]);
      }
    }
  }
}

// ------------------------------------------------------------------------------------------------
// SVG backend.

std::string Hex(const Rgb& c) { return fmt::format("#{:02x}{:02x}{:02x}", c.r, c.g, c.b); }

std::string EscapeXml(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        // Control characters are not allowed in XML 1.0.
        if (static_cast<unsigned char>(c) >= 0x20 || c == '\t') out += c;
    }
  }
  return out;
}

void SvgPolyline(std::string& out, const PolylineShape& line) {
  if (line.points.empty()) return;
  if (line.points.size() == 1) {
    out += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:.1f}\" fill=\"{}\"/>\n",
                       line.points[0].x, line.points[0].y, DotRadius(line), Hex(line.color));
    return;
  }
  out += fmt::format("<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"{:.1f}\"",
                     Hex(line.color), line.width);
  if (line.dashed) out += fmt::format(" stroke-dasharray=\"{} {}\"", kDashOn, kDashOff);
  out += " points=\"";
  for (size_t i = 0; i < line.points.size(); ++i) {
    out += fmt::format("{}{:.1f},{:.1f}", i == 0 ? "" : " ", line.points[i].x, line.points[i].y);
  }
  out += "\"/>\n";
}

void SvgRect(std::string& out, const RectShape& shape) {
  if (shape.filled) {
    out += fmt::format(
        "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\"/>\n",
        shape.rect.x, shape.rect.y, shape.rect.width, shape.rect.height, Hex(shape.fill));
    return;
  }
  // Inset by half the stroke so that the outline covers the same pixels as in the raster.
  const double h = shape.width / 2.0;
  out += fmt::format(
      "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"none\" "
      "stroke=\"{}\" stroke-width=\"{:.1f}\"/>\n",
      shape.rect.x + h, shape.rect.y + h, shape.rect.width - 2 * h, shape.rect.height - 2 * h,
      Hex(shape.fill), shape.width);
}

void SvgText(std::string& out, const TextShape& shape) {
  const char* anchor = shape.anchor == Anchor::kStart    ? "start"
                       : shape.anchor == Anchor::kMiddle ? "middle"
                                                         : "end";
  out += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"{:.1f}\" fill=\"{}\"",
                     shape.baseline.x, shape.baseline.y, shape.size, Hex(shape.color));
  if (anchor[0] != 's') out += fmt::format(" text-anchor=\"{}\"", anchor);
  if (shape.bold) out += " font-weight=\"bold\"";
  if (shape.vertical) {
    out +=
        fmt::format(" transform=\"rotate(-90 {:.1f} {:.1f})\"", shape.baseline.x, shape.baseline.y);
  }
  out += ">" + EscapeXml(shape.text) + "</text>\n";
}

}  // namespace

double TextWidth(const std::string& text, double size, bool bold) {
  int baseline = 0;
  return cv::getTextSize(AsciiOnly(text), kFont, FontScale(size), bold ? 2 : 1, &baseline).width;
}

cv::Mat RenderRaster(const Figure& figure) {
  cv::Mat image(figure.height, figure.width, CV_8UC3, cv::Scalar(255, 255, 255));
  for (const Shape& shape : figure.shapes) {
    if (const auto* line = std::get_if<PolylineShape>(&shape)) {
      DrawPolyline(image, *line);
    } else if (const auto* rect = std::get_if<RectShape>(&shape)) {
      DrawRect(image, *rect);
    } else if (const auto* circle = std::get_if<CircleShape>(&shape)) {
      cv::circle(image, Fixed(circle->center),
                 static_cast<int>(std::lround(circle->radius * kShiftScale)), Bgr(circle->fill),
                 cv::FILLED, cv::LINE_AA, kShift);
    } else {
      DrawText(image, std::get<TextShape>(shape));
    }
  }
  return image;
}

std::string RenderSvg(const Figure& figure) {
  std::string out = fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"{0}\" height=\"{1}\" "
      "viewBox=\"0 0 {0} {1}\">\n"
      "<g font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\" stroke-linejoin=\"round\" "
      "stroke-linecap=\"round\">\n"
      "<rect x=\"0\" y=\"0\" width=\"{0}\" height=\"{1}\" fill=\"#ffffff\"/>\n",
      figure.width, figure.height);
  for (const Shape& shape : figure.shapes) {
    if (const auto* line = std::get_if<PolylineShape>(&shape)) {
      SvgPolyline(out, *line);
    } else if (const auto* rect = std::get_if<RectShape>(&shape)) {
      SvgRect(out, *rect);
    } else if (const auto* circle = std::get_if<CircleShape>(&shape)) {
      out += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:.1f}\" fill=\"{}\"/>\n",
                         circle->center.x, circle->center.y, circle->radius, Hex(circle->fill));
    } else {
      SvgText(out, std::get<TextShape>(shape));
    }
  }
  out += "</g>\n</svg>\n";
  return out;
}

}  // namespace moslam::eval::internal
