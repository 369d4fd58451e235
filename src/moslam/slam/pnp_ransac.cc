#include "moslam/slam/pnp_ransac.h"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::slam {

void PnpRansacOptions::Check() const {
  if (!(probability > 0.0 && probability < 1.0)) {
    throw InputError("PnpRansacOptions.probability must be in (0, 1)");
  }
  if (min_inliers < 4) throw InputError("PnpRansacOptions.min_inliers must be >= 4");
  if (max_iterations < 1) throw InputError("PnpRansacOptions.max_iterations must be >= 1");
  if (!(chi2 > 0.0)) throw InputError("PnpRansacOptions.chi2 must be > 0");
  if (refine_rounds < 0) throw InputError("PnpRansacOptions.refine_rounds must be >= 0");
}

namespace {

geometry::SE3 ToSE3(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R_cv;
  cv::Rodrigues(rvec, R_cv);
  Eigen::Matrix3d R;
  cv::cv2eigen(R_cv, R);
  return geometry::SE3(R,
                       Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
}

void ToRvecTvec(const geometry::SE3& T, cv::Mat* rvec, cv::Mat* tvec) {
  cv::Mat R_cv;
  cv::eigen2cv(Eigen::Matrix3d(T.rotation_matrix()), R_cv);
  cv::Rodrigues(R_cv, *rvec);
  *tvec = (cv::Mat_<double>(3, 1) << T.translation().x(), T.translation().y(), T.translation().z());
}

// ORB-SLAM2's CheckInliers: squared reprojection error within chi2 * sigma2 of the level, and
// the point in front of the camera.
int Classify(const geometry::SE3& T, const std::vector<Eigen::Vector3d>& points,
             const std::vector<Eigen::Vector2d>& pixels, const std::vector<float>& sigma2,
             const optim::CameraModel& cam, double chi2, std::vector<bool>* inlier) {
  int n = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d pc = T * points[i];
    bool ok = pc.z() > 0.0;
    if (ok) {
      const double u = cam.fx * pc.x() / pc.z() + cam.cx;
      const double v = cam.fy * pc.y() / pc.z() + cam.cy;
      const double e2 = (Eigen::Vector2d(u, v) - pixels[i]).squaredNorm();
      ok = e2 <= chi2 * sigma2[i];
    }
    (*inlier)[i] = ok;
    n += ok ? 1 : 0;
  }
  return n;
}

// One Levenberg-Marquardt re-estimate from the inliers, starting at T.
geometry::SE3 Refine(const geometry::SE3& T, const std::vector<cv::Point3d>& object,
                     const std::vector<cv::Point2d>& image, const std::vector<bool>& inlier,
                     const cv::Mat& K) {
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  for (size_t i = 0; i < inlier.size(); ++i) {
    if (!inlier[i]) continue;
    obj.push_back(object[i]);
    img.push_back(image[i]);
  }
  cv::Mat rvec, tvec;
  ToRvecTvec(T, &rvec, &tvec);
  if (!cv::solvePnP(obj, img, K, cv::noArray(), rvec, tvec, /*useExtrinsicGuess=*/true,
                    cv::SOLVEPNP_ITERATIVE)) {
    return T;
  }
  return ToSE3(rvec, tvec);
}

}  // namespace

PnpRansacResult SolvePnpRansac(const std::vector<Eigen::Vector3d>& points_world,
                               const std::vector<Eigen::Vector2d>& pixels,
                               const std::vector<float>& level_sigma2,
                               const optim::CameraModel& camera, const PnpRansacOptions& options) {
  options.Check();
  MOSLAM_CHECK(points_world.size() == pixels.size() && pixels.size() == level_sigma2.size());
  const size_t n = points_world.size();
  PnpRansacResult result;
  result.inlier.assign(n, false);
  if (static_cast<int>(n) < std::max(options.min_inliers, 5)) return result;

  std::vector<cv::Point3d> object(n);
  std::vector<cv::Point2d> image(n);
  for (size_t i = 0; i < n; ++i) {
    object[i] = cv::Point3d(points_world[i].x(), points_world[i].y(), points_world[i].z());
    image[i] = cv::Point2d(pixels[i].x(), pixels[i].y());
  }
  const cv::Mat K = (cv::Mat_<double>(3, 3) << camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy,
                     0.0, 0.0, 1.0);
  // OpenCV's single threshold: the per-keypoint one at the median level of the correspondences;
  // the refinement below applies the per-keypoint thresholds.
  std::vector<float> sorted = level_sigma2;
  std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.end());
  const double threshold = std::sqrt(options.chi2 * sorted[n / 2]);
  cv::Mat rvec, tvec;
  std::vector<int> ransac_inliers;
  const int flags =
      options.solver == PnpMinimalSolver::kAp3p ? cv::SOLVEPNP_AP3P : cv::SOLVEPNP_EPNP;
  bool found = false;
  try {
    found = cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false,
                               options.max_iterations, static_cast<float>(threshold),
                               options.probability, ransac_inliers, flags);
  } catch (const cv::Exception&) {
    // Degenerate samples (all points collinear, ...) make some minimal solvers throw; that is
    // a failed RANSAC, an expected outcome.
    found = false;
  }
  if (!found || static_cast<int>(ransac_inliers.size()) < options.min_inliers) return result;

  geometry::SE3 T = ToSE3(rvec, tvec);
  std::vector<bool> inlier(n, false);
  int num = Classify(T, points_world, pixels, level_sigma2, camera, options.chi2, &inlier);
  for (int round = 0; round < options.refine_rounds && num >= options.min_inliers; ++round) {
    const geometry::SE3 refined = Refine(T, object, image, inlier, K);
    std::vector<bool> next(n, false);
    const int num_next =
        Classify(refined, points_world, pixels, level_sigma2, camera, options.chi2, &next);
    if (num_next < num) break;  // keep the better pose
    const bool stable = next == inlier;
    T = refined;
    inlier = std::move(next);
    num = num_next;
    if (stable) break;
  }
  if (num < options.min_inliers) return result;
  result.success = true;
  result.T_cam_world = T;
  result.inlier = std::move(inlier);
  result.num_inliers = num;
  return result;
}

}  // namespace moslam::slam
