#include "moslam/camera/distortion.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#ifdef MOSLAM_HAVE_CV_CALIB3D
#include <opencv2/calib3d.hpp>
#endif
#include <opencv2/core.hpp>

#include "moslam/util/error.h"

namespace moslam::camera {
namespace {

// EuRoC MAV cam0 (Burri et al. 2016) and TUM fr1 (Sturm et al. 2012) calibrations: moderate
// real-world distortion, the latter with a strong k3.
struct Lens {
  const char* name;
  double fx, fy, cx, cy;
  int width, height;
  Distortion d;
};

const Lens kEuroc{
    "euroc_cam0", 458.654, 457.296, 367.215,
    248.375,      752,     480,     {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0.0}};
const Lens kTumFr1{
    "tum_fr1",  517.306408, 516.469215, 318.643040,
    255.313989, 640,        480,        {0.262383, -0.953104, -0.005358, 0.002628, 1.163314}};

// A grid of distorted pixels covering the whole image, corners included.
std::vector<Eigen::Vector2d> PixelGrid(const Lens& lens, int step) {
  std::vector<Eigen::Vector2d> pixels;
  for (int v = 0; v <= lens.height; v += step) {
    for (int u = 0; u <= lens.width; u += step) {
      pixels.emplace_back(std::min(u, lens.width - 1), std::min(v, lens.height - 1));
    }
  }
  return pixels;
}

Eigen::Vector2d ToNormalized(const Lens& lens, const Eigen::Vector2d& px) {
  return {(px.x() - lens.cx) / lens.fx, (px.y() - lens.cy) / lens.fy};
}

Eigen::Vector2d ToPixel(const Lens& lens, const Eigen::Vector2d& n) {
  return {lens.fx * n.x() + lens.cx, lens.fy * n.y() + lens.cy};
}

TEST(Distortion, ZeroDistortionIsIdentity) {
  const Distortion none;
  EXPECT_TRUE(none.IsZero());
  const Eigen::Vector2d x(0.3, -0.7);
  EXPECT_EQ(Distort(none, x), x);
  EXPECT_EQ(Undistort(none, x), x);
  EXPECT_TRUE(DistortJacobian(none, x).isIdentity(0.0));
}

TEST(Distortion, MatchesTheFormulaOnAKnownPoint) {
  const Distortion d{0.1, 0.01, 0.001, 0.002, 0.0001};
  const double x = 0.5, y = -0.25;
  const double r2 = x * x + y * y;
  const double radial = 1 + 0.1 * r2 + 0.01 * r2 * r2 + 0.0001 * r2 * r2 * r2;
  const Eigen::Vector2d expected(x * radial + 2 * 0.001 * x * y + 0.002 * (r2 + 2 * x * x),
                                 y * radial + 0.001 * (r2 + 2 * y * y) + 2 * 0.002 * x * y);
  EXPECT_NEAR((Distort(d, {x, y}) - expected).norm(), 0.0, 1e-15);
  EXPECT_EQ(d.Coefficients(), (std::array<double, 5>{0.1, 0.01, 0.001, 0.002, 0.0001}));
}

TEST(Distortion, JacobianMatchesFiniteDifferences) {
  const Eigen::Vector2d x(0.4, -0.3);
  for (const Lens& lens : {kEuroc, kTumFr1}) {
    const Eigen::Matrix2d analytic = DistortJacobian(lens.d, x);
    Eigen::Matrix2d numeric;
    const double h = 1e-6;
    for (int i = 0; i < 2; ++i) {
      const Eigen::Vector2d step = Eigen::Vector2d::Unit(i) * h;
      numeric.col(i) = (Distort(lens.d, x + step) - Distort(lens.d, x - step)) / (2 * h);
    }
    EXPECT_LT((analytic - numeric).cwiseAbs().maxCoeff(), 1e-8) << lens.name;
  }
}

TEST(Distortion, UndistortInvertsDistortOverTheImage) {
  for (const Lens& lens : {kEuroc, kTumFr1}) {
    double worst_px = 0.0;
    for (const Eigen::Vector2d& px : PixelGrid(lens, 8)) {
      const Eigen::Vector2d distorted = ToNormalized(lens, px);
      const Eigen::Vector2d ideal = Undistort(lens.d, distorted);
      worst_px = std::max(worst_px, (ToPixel(lens, Distort(lens.d, ideal)) - px).norm());
    }
    EXPECT_LT(worst_px, 1e-8) << lens.name;
  }
}

TEST(Distortion, ConvergesWhereTheFixedPointIterationDiverges) {
  // Beyond the image border of TUM fr1 (r > 0.9) and for strong barrel distortion (r > 1.1) the
  // fixed-point iteration of OpenCV oscillates and diverges; the Newton steps still invert.
  const Distortion barrel{-0.6, 0.3, 0.0, 0.0, 0.0};
  for (const Distortion& d : {kTumFr1.d, barrel}) {
    for (double r = 0.1; r <= 1.4; r += 0.05) {
      for (double angle = 0.0; angle < 6.28; angle += 0.5) {
        const Eigen::Vector2d ideal(r * std::cos(angle), r * std::sin(angle));
        const Eigen::Vector2d back = Undistort(d, Distort(d, ideal));
        EXPECT_LT((back - ideal).norm(), 1e-9) << "r " << r << " angle " << angle;
      }
    }
  }
}

TEST(Distortion, CheckRejectsNonFiniteCoefficients) {
  Distortion d{0.1, 0.0, 0.0, 0.0, 0.0};
  EXPECT_NO_THROW(d.Check());
  d.p2 = std::numeric_limits<double>::quiet_NaN();
  try {
    d.Check();
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("p2"), std::string::npos) << e.what();
  }
}

#ifdef MOSLAM_HAVE_CV_CALIB3D

// cv::undistortPoints with P = K returns ideal pixels.
std::vector<cv::Point2d> OpenCvUndistort(const Lens& lens, const std::vector<Eigen::Vector2d>& px,
                                         const cv::TermCriteria* criteria) {
  std::vector<cv::Point2d> src, dst;
  for (const auto& p : px) src.emplace_back(p.x(), p.y());
  const cv::Matx33d k(lens.fx, 0, lens.cx, 0, lens.fy, lens.cy, 0, 0, 1);
  const auto c = lens.d.Coefficients();
  const cv::Vec<double, 5> dist(c[0], c[1], c[2], c[3], c[4]);
  if (criteria != nullptr) {
    cv::undistortPoints(src, dst, k, dist, cv::noArray(), k, *criteria);
  } else {
    cv::undistortPoints(src, dst, k, dist, cv::noArray(), k);
  }
  return dst;
}

TEST(Distortion, MatchesOpenCvUndistortPointsRunToConvergence) {
  // OpenCV's default stops after 5 iterations; with a count-and-epsilon criterion it runs the
  // same fixed point to convergence, which is what moslam computes.
  const cv::TermCriteria converge(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 1000, 1e-13);
  for (const Lens& lens : {kEuroc, kTumFr1}) {
    const std::vector<Eigen::Vector2d> pixels = PixelGrid(lens, 16);
    const std::vector<cv::Point2d> reference = OpenCvUndistort(lens, pixels, &converge);
    ASSERT_EQ(reference.size(), pixels.size());
    double worst = 0.0;
    for (size_t i = 0; i < pixels.size(); ++i) {
      const Eigen::Vector2d ours = ToPixel(lens, Undistort(lens.d, ToNormalized(lens, pixels[i])));
      worst = std::max(worst, (ours - Eigen::Vector2d(reference[i].x, reference[i].y)).norm());
    }
    EXPECT_LT(worst, 1e-6) << lens.name;
  }
}

TEST(Distortion, AtLeastAsAccurateAsOpenCvDefaultIterations) {
  for (const Lens& lens : {kEuroc, kTumFr1}) {
    const std::vector<Eigen::Vector2d> pixels = PixelGrid(lens, 32);
    const std::vector<cv::Point2d> opencv = OpenCvUndistort(lens, pixels, nullptr);
    for (size_t i = 0; i < pixels.size(); ++i) {
      const Eigen::Vector2d ours = Undistort(lens.d, ToNormalized(lens, pixels[i]));
      const Eigen::Vector2d theirs = ToNormalized(lens, {opencv[i].x, opencv[i].y});
      const double our_error = (ToPixel(lens, Distort(lens.d, ours)) - pixels[i]).norm();
      const double their_error = (ToPixel(lens, Distort(lens.d, theirs)) - pixels[i]).norm();
      EXPECT_LE(our_error, their_error + 1e-9) << lens.name << " pixel " << pixels[i].transpose();
    }
  }
}

TEST(Distortion, DistortMatchesOpenCvProjectPoints) {
  for (const Lens& lens : {kEuroc, kTumFr1}) {
    std::vector<cv::Point3d> points;
    for (double x = -0.7; x <= 0.7; x += 0.35) {
      for (double y = -0.5; y <= 0.5; y += 0.25) points.emplace_back(x, y, 1.0);
    }
    const cv::Matx33d k(lens.fx, 0, lens.cx, 0, lens.fy, lens.cy, 0, 0, 1);
    const auto c = lens.d.Coefficients();
    std::vector<cv::Point2d> projected;
    cv::projectPoints(points, cv::Vec3d::zeros(), cv::Vec3d::zeros(), k,
                      cv::Vec<double, 5>(c[0], c[1], c[2], c[3], c[4]), projected);
    for (size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector2d ours = ToPixel(lens, Distort(lens.d, {points[i].x, points[i].y}));
      EXPECT_LT((ours - Eigen::Vector2d(projected[i].x, projected[i].y)).norm(), 1e-9);
    }
  }
}

#else

TEST(Distortion, MatchesOpenCvUndistortPointsRunToConvergence) {
  GTEST_SKIP() << "OpenCV calib3d not available: comparison with cv::undistortPoints skipped";
}

#endif

}  // namespace
}  // namespace moslam::camera
