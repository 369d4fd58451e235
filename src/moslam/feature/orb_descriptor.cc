#include "moslam/feature/orb_descriptor.h"

#include <cmath>
#include <cstdlib>

#include <opencv2/core/fast_math.hpp>
#include <opencv2/core/hal/intrin.hpp>

#include "moslam/feature/orb_pattern.h"

namespace moslam::feature {
namespace {

constexpr float kDegreesPerRadian = static_cast<float>(180.0 / CV_PI);
constexpr int kNumPoints = 512;  // 256 tests, two points each

// kOrbPattern as float coordinates, point 2k = first point of test k, 2k + 1 = second, laid out
// for vector loads.
struct PatternPoints {
  alignas(16) float x[kNumPoints];
  alignas(16) float y[kNumPoints];
};

const PatternPoints& Points() {
  static const PatternPoints points = [] {
    PatternPoints p{};
    for (int k = 0; k < 256; ++k) {
      p.x[2 * k] = kOrbPattern[k][0];
      p.y[2 * k] = kOrbPattern[k][1];
      p.x[2 * k + 1] = kOrbPattern[k][2];
      p.y[2 * k + 1] = kOrbPattern[k][3];
    }
    return p;
  }();
  return points;
}

const std::array<int, kOrbHalfPatch + 1>& HalfWidths() {
  static const std::array<int, kOrbHalfPatch + 1> half_widths = CircularPatchHalfWidths();
  return half_widths;
}

// Weights of the image moments over the circular patch, one row of 32 16-bit lanes per patch
// row (u = -15..16; zero outside the disk): u for m10, v for m01.
struct MomentWeights {
  alignas(16) int16_t u[kOrbPatchSize][32];
  alignas(16) int16_t v[kOrbPatchSize][32];
};

const MomentWeights& Weights() {
  static const MomentWeights weights = [] {
    MomentWeights w{};
    const std::array<int, kOrbHalfPatch + 1>& half_widths = HalfWidths();
    for (int r = 0; r < kOrbPatchSize; ++r) {
      const int v = r - kOrbHalfPatch;
      for (int k = 0; k < 32; ++k) {
        const int u = k - kOrbHalfPatch;
        const bool inside = std::abs(u) <= half_widths[std::abs(v)];
        w.u[r][k] = static_cast<int16_t>(inside ? u : 0);
        w.v[r][k] = static_cast<int16_t>(inside ? v : 0);
      }
    }
    return w;
  }();
  return weights;
}

}  // namespace

std::array<int, kOrbHalfPatch + 1> CircularPatchHalfWidths() {
  std::array<int, kOrbHalfPatch + 1> half_widths{};
  const int r2 = kOrbHalfPatch * (kOrbHalfPatch + 1);
  for (int v = 0; v <= kOrbHalfPatch; ++v) {
    int u = 0;
    while ((u + 1) * (u + 1) + v * v <= r2) ++u;
    half_widths[v] = u;
  }
  return half_widths;
}

float IntensityCentroidAngle(const cv::Mat& image, int x, int y) {
  const int step = static_cast<int>(image.step1());
  const uint8_t* const center = image.ptr<uint8_t>(y) + x;
  int m10 = 0;
  int m01 = 0;
#if CV_SIMD128
  // Each row of the patch is 32 pixels (u = -15..16) weighted by the tables, which are zero
  // outside the disk: 2 loads and 8 multiply-adds of 16-bit lanes per row.
  const MomentWeights& weights = Weights();
  cv::v_int32x4 acc10 = cv::v_setzero_s32();
  cv::v_int32x4 acc01 = cv::v_setzero_s32();
  for (int r = 0; r < kOrbPatchSize; ++r) {
    const uint8_t* row = center + (r - kOrbHalfPatch) * step - kOrbHalfPatch;
    cv::v_uint16x8 p[4];
    cv::v_expand(cv::v_load(row), p[0], p[1]);
    cv::v_expand(cv::v_load(row + 16), p[2], p[3]);
    for (int k = 0; k < 4; ++k) {
      const cv::v_int16x8 pixels = cv::v_reinterpret_as_s16(p[k]);
      acc10 += cv::v_dotprod(pixels, cv::v_load(weights.u[r] + 8 * k));
      acc01 += cv::v_dotprod(pixels, cv::v_load(weights.v[r] + 8 * k));
    }
  }
  m10 = cv::v_reduce_sum(acc10);
  m01 = cv::v_reduce_sum(acc01);
#else
  const std::array<int, kOrbHalfPatch + 1>& half_widths = HalfWidths();
  for (int v = -kOrbHalfPatch; v <= kOrbHalfPatch; ++v) {
    const uint8_t* row = center + v * step;
    const int w = half_widths[v < 0 ? -v : v];
    for (int u = -w; u <= w; ++u) {
      m10 += u * row[u];
      m01 += v * row[u];
    }
  }
#endif
  float angle = std::atan2(static_cast<float>(m01), static_cast<float>(m10)) * kDegreesPerRadian;
  if (angle < 0) angle += 360.0f;
  if (angle >= 360.0f) angle -= 360.0f;
  return angle;
}

void SteeredBrief(const cv::Mat& smoothed, int x, int y, float angle_deg, uint8_t* descriptor) {
  const uint8_t* center = smoothed.ptr<uint8_t>(y) + x;
  const int step = static_cast<int>(smoothed.step1());
  const float angle = angle_deg / kDegreesPerRadian;
  const float c = std::cos(angle);
  const float s = std::sin(angle);
  // A pattern point (px, py) rotated by the keypoint angle lands on (c px - s py, s px + c py),
  // rounded to the nearest pixel (ties to even, like cvRound). The 512 memory offsets are computed
  // four at a time; this loop is most of the descriptor's cost.
  const PatternPoints& points = Points();
  alignas(16) int32_t offsets[kNumPoints];
#if CV_SIMD128
  const cv::v_float32x4 vc = cv::v_setall_f32(c);
  const cv::v_float32x4 vs = cv::v_setall_f32(s);
  const cv::v_int32x4 vstep = cv::v_setall_s32(step);
  for (int k = 0; k < kNumPoints; k += 4) {
    const cv::v_float32x4 px = cv::v_load_aligned(points.x + k);
    const cv::v_float32x4 py = cv::v_load_aligned(points.y + k);
    const cv::v_int32x4 rx = cv::v_round(vc * px - vs * py);
    const cv::v_int32x4 ry = cv::v_round(vs * px + vc * py);
    cv::v_store_aligned(offsets + k, ry * vstep + rx);
  }
#else
  for (int k = 0; k < kNumPoints; ++k) {
    offsets[k] = cvRound(s * points.x[k] + c * points.y[k]) * step +
                 cvRound(c * points.x[k] - s * points.y[k]);
  }
#endif
  const int32_t* pair = offsets;
  for (int byte = 0; byte < kOrbDescriptorBytes; ++byte) {
    unsigned value = 0;
    for (int bit = 0; bit < 8; ++bit, pair += 2) {
      value |= static_cast<unsigned>(center[pair[0]] < center[pair[1]]) << bit;
    }
    descriptor[byte] = static_cast<uint8_t>(value);
  }
}

}  // namespace moslam::feature
