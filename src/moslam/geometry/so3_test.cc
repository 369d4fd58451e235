#include "moslam/geometry/so3.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "moslam/geometry/test_util.h"

namespace moslam::geometry {
namespace {

using test::MatricesNear;

TEST(SO3, HatIsTheCrossProductAndVeeItsInverse) {
  std::mt19937 rng(1);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d a = test::RandomVector(rng, 2), b = test::RandomVector(rng, 2);
    EXPECT_TRUE(MatricesNear(Hat(a) * b, a.cross(b), 1e-12));
    EXPECT_TRUE(MatricesNear(Vee(Hat(a)), a, 0));
  }
}

TEST(SO3, ExpMatchesAngleAxis) {
  std::mt19937 rng(2);
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d w = test::RandomVector(rng, 3);
    const Eigen::Matrix3d expected = Eigen::AngleAxisd(w.norm(), w.normalized()).matrix();
    EXPECT_TRUE(MatricesNear(ExpSO3(w).toRotationMatrix(), expected, 1e-12));
  }
}

TEST(SO3, LogInvertsExpIncludingTinyAndNearPiAngles) {
  std::mt19937 rng(3);
  for (double angle : {0.0, 1e-12, 1e-8, 1e-5, 1e-3, 0.5, 2.0, M_PI - 1e-6, M_PI - 1e-9}) {
    const Eigen::Vector3d axis = test::RandomVector(rng, 1).normalized();
    const Eigen::Vector3d w = angle * axis;
    EXPECT_TRUE(MatricesNear(LogSO3(ExpSO3(w)), w, 1e-9 * std::max(1.0, angle)))
        << "angle " << angle;
    EXPECT_NEAR(RotationAngle(ExpSO3(w)), angle, 1e-9);
  }
}

TEST(SO3, LogIsInvariantToQuaternionSign) {
  const Eigen::Quaterniond q = ExpSO3({0.3, -0.2, 0.1});
  Eigen::Quaterniond neg = q;
  neg.coeffs() = -neg.coeffs();
  EXPECT_TRUE(MatricesNear(LogSO3(q), LogSO3(neg), 1e-14));
}

// J(phi) is the derivative of Exp along a path: Exp(phi + d) ~ Exp(J d) Exp(phi).
TEST(SO3, LeftJacobianMatchesNumericDifferentiation) {
  std::mt19937 rng(4);
  const double h = 1e-6;
  for (double scale : {1e-6, 0.1, 1.0, 2.5}) {
    const Eigen::Vector3d phi = test::RandomVector(rng, scale);
    Eigen::Matrix3d numeric;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d d = h * Eigen::Vector3d::Unit(k);
      const Eigen::Vector3d plus = LogSO3(ExpSO3(phi + d) * ExpSO3(phi).conjugate());
      const Eigen::Vector3d minus = LogSO3(ExpSO3(phi - d) * ExpSO3(phi).conjugate());
      numeric.col(k) = (plus - minus) / (2 * h);
    }
    EXPECT_TRUE(MatricesNear(LeftJacobianSO3(phi), numeric, 1e-7)) << "scale " << scale;
    EXPECT_TRUE(MatricesNear(LeftJacobianSO3(phi) * LeftJacobianInverseSO3(phi),
                             Eigen::Matrix3d::Identity(), 1e-12));
  }
}

TEST(SO3, NearestRotationRepairsAPerturbedMatrix) {
  const Eigen::Matrix3d R = ExpSO3({0.4, 0.1, -0.7}).toRotationMatrix();
  Eigen::Matrix3d noisy = R;
  noisy(0, 1) += 1e-4;
  noisy(2, 2) -= 2e-4;
  const Eigen::Matrix3d fixed = NearestRotation(noisy);
  EXPECT_TRUE(MatricesNear(fixed * fixed.transpose(), Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_NEAR(fixed.determinant(), 1.0, 1e-12);
  EXPECT_TRUE(MatricesNear(fixed, R, 3e-4));
}

}  // namespace
}  // namespace moslam::geometry
