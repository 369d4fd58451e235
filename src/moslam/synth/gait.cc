#include "moslam/synth/gait.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace moslam::synth {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;
using geometry::SE3;

constexpr double kDeg = M_PI / 180.0;
constexpr double kToeOff = 0.6;              // stance share of the cycle (Perry & Burnfield)
constexpr double kHeelRocker = 0.08;         // heel strike until the foot is flat
constexpr double kHeelRise = 0.4;            // the heel lifts from here to toe off
constexpr double kStrikePitch = 4 * kDeg;    // toes up at heel strike (ball 1.7 cm up)
constexpr double kToeOffPitch = -35 * kDeg;  // heel up at toe off
constexpr double kToeOut = 5 * kDeg;
constexpr double kAhead = 0.25;  // footprint ahead of the pelvis at heel strike, strides

Matrix3d RotZ(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitZ()).toRotationMatrix(); }
// About the lateral axis: + swings a hanging limb forward, tips a foot's toes up.
Matrix3d Swing(double a) { return Eigen::AngleAxisd(-a, Vector3d::UnitY()).toRotationMatrix(); }
Matrix3d Roll(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitX()).toRotationMatrix(); }

// Minimum-jerk profile on [0, 1] (Flash & Hogan 1985): smooth start and end.
double Smooth(double p) {
  p = std::clamp(p, 0.0, 1.0);
  return p * p * p * (10 - 15 * p + 6 * p * p);
}

double WrapAngle(double a) { return std::remainder(a, 2 * M_PI); }

struct Footprint {
  Vector3d ground;  // ankle's ground point with the foot flat
  double heading;
};

Footprint FootprintAt(const Skeleton& sk, const PathFunction& path, double s_strike, double stride,
                      int side) {
  Vector2d xy;
  double heading = 0.0;
  path(s_strike + kAhead * stride, &xy, &heading);
  const Vector2d left(-std::sin(heading), std::cos(heading));
  const double half_width = std::abs(sk.joint[kThighL].y()) * 1.05;
  const Vector2d p = xy + side * half_width * left;
  return {Vector3d(p.x(), p.y(), 0.0), heading + side * kToeOut};
}

// The ankle of a foot flat at `print`, pitched by `pitch` about its heel (pitch > 0) or its ball
// (pitch < 0): the pivot stays on the ground.
Vector3d AnkleAt(const Skeleton& sk, const Footprint& print, double pitch) {
  const Matrix3d R_flat = RotZ(print.heading);
  const Matrix3d R = R_flat * Swing(pitch);
  const double h = sk.ankle_height;
  const Vector3d pivot_local = pitch >= 0 ? Vector3d(-sk.heel, 0, -h) : Vector3d(sk.ball, 0, -h);
  const Vector3d pivot_world = print.ground + R_flat * Vector3d(pivot_local.x(), 0, 0);
  return pivot_world - R * pivot_local;
}

double SideOffset(double stride, int side) { return side > 0 ? 0.0 : 0.5 * stride; }

// Two-bone inverse kinematics: thigh and shin frames that put the ankle at `ankle` (pulled
// towards the hip when out of reach), knee forward along `forward`. Returns the ankle reached.
Vector3d LegIk(const Vector3d& hip, Vector3d ankle, const Vector3d& forward, double a, double b,
               SE3* T_thigh, SE3* T_shin) {
  Vector3d d = ankle - hip;
  double D = d.norm();
  const Vector3d dir = D > 1e-9 ? Vector3d(d / D) : Vector3d(-Vector3d::UnitZ());
  D = std::clamp(D, std::abs(a - b) + 1e-6, 0.9995 * (a + b));
  ankle = hip + dir * D;
  const double x = (a * a - b * b + D * D) / (2 * D);
  const double h = std::sqrt(std::max(0.0, a * a - x * x));
  Vector3d f = forward - forward.dot(dir) * dir;
  if (f.norm() < 1e-9) f = Vector3d::UnitX() - Vector3d::UnitX().dot(dir) * dir;
  f.normalize();
  const Vector3d knee = hip + x * dir + h * f;
  auto frame = [&](const Vector3d& top, const Vector3d& bottom) {
    const Vector3d z = (top - bottom).normalized();
    const Vector3d xa = (f - f.dot(z) * z).normalized();
    Matrix3d R;
    R.col(0) = xa;
    R.col(1) = z.cross(xa);
    R.col(2) = z;
    return SE3(R, top);
  };
  *T_thigh = frame(hip, knee);
  *T_shin = frame(knee, ankle);
  return ankle;
}

SE3 Child(const Skeleton& sk, const SE3& T_parent, int parent, int child, const Matrix3d& R) {
  return T_parent *
         SE3(R, sk.joint[static_cast<size_t>(child)] - sk.joint[static_cast<size_t>(parent)]);
}

void Arms(const Skeleton& sk, BodyPose* pose, const double flex[2], const double elbow[2],
          double abduct) {
  for (int i = 0; i < 2; ++i) {
    const int side = i == 0 ? 1 : -1;
    const int upper = side > 0 ? kUpperArmL : kUpperArmR;
    const SE3 T_upper =
        Child(sk, (*pose)[kChest], kChest, upper, Roll(side * abduct) * Swing(flex[i]));
    (*pose)[static_cast<size_t>(upper)] = T_upper;
    const SE3 T_fore = Child(sk, T_upper, upper, upper + 1, Swing(elbow[i]));
    (*pose)[static_cast<size_t>(upper + 1)] = T_fore;
    (*pose)[static_cast<size_t>(upper + 2)] =
        Child(sk, T_fore, upper + 1, upper + 2, Swing(5 * kDeg));
  }
}

}  // namespace

double StrideLength(double height_m, double speed) {
  return std::clamp(1.45 * (height_m / 1.75) * std::sqrt(std::max(speed, 0.05) / 1.3), 0.3, 2.2);
}

FootPlacement PlaceFoot(const Skeleton& sk, const PathFunction& path, double s, double stride,
                        int side) {
  const double offset = SideOffset(stride, side);
  const double u = (s - offset) / stride;
  const double k = std::floor(u);
  const double phase = u - k;
  const Footprint now = FootprintAt(sk, path, k * stride + offset, stride, side);
  FootPlacement out;
  out.phase = phase;
  out.stance = phase < kToeOff;
  double pitch = 0.0, heading = now.heading;
  Vector3d ankle;
  if (phase < kToeOff) {
    if (phase < kHeelRocker) {
      pitch = kStrikePitch * (1 - Smooth(phase / kHeelRocker));
    } else if (phase >= kHeelRise) {
      pitch = kToeOffPitch * Smooth((phase - kHeelRise) / (kToeOff - kHeelRise));
    }
    ankle = AnkleAt(sk, now, pitch);
  } else {
    const Footprint next = FootprintAt(sk, path, (k + 1) * stride + offset, stride, side);
    const double p = (phase - kToeOff) / (1 - kToeOff);
    const Vector3d from = AnkleAt(sk, now, kToeOffPitch), to = AnkleAt(sk, next, kStrikePitch);
    const double m = Smooth(p);
    ankle = from + m * (to - from) + Vector3d(0, 0, 0.045 * sk.thigh / 0.245 * std::sin(M_PI * p));
    heading = now.heading + m * WrapAngle(next.heading - now.heading);
    pitch = p < 0.5 ? kToeOffPitch * (1 - Smooth(p / 0.5)) : kStrikePitch * Smooth((p - 0.5) / 0.5);
  }
  out.T_world_foot = SE3(RotZ(heading) * Swing(pitch), ankle);
  return out;
}

BodyPose WalkingPose(const Skeleton& sk, const PathFunction& path, double s, double stride,
                     double head_yaw) {
  BodyPose pose;
  Vector2d xy;
  double heading = 0.0;
  path(s, &xy, &heading);
  const FootPlacement feet[2] = {PlaceFoot(sk, path, s, stride, 1),
                                 PlaceFoot(sk, path, s, stride, -1)};
  const double phase_l = feet[0].phase;
  const Vector2d left(-std::sin(heading), std::cos(heading));
  const double H = sk.thigh / 0.245;
  const Vector2d hips_xy = xy + 0.012 * H * std::cos(2 * M_PI * (phase_l - 0.3)) * left;
  const double yaw = heading - 4 * kDeg * std::cos(2 * M_PI * phase_l);
  const Matrix3d R_pelvis = RotZ(yaw);
  // Hip height: a slightly flexed stance, lowered where a stance leg could not reach its foot.
  const double leg = sk.thigh + sk.shin;
  double z = 0.965 * (leg + sk.ankle_height);
  for (int i = 0; i < 2; ++i) {
    if (!feet[i].stance) continue;
    const int thigh = i == 0 ? kThighL : kThighR;
    const Vector3d hip_offset =
        R_pelvis * (sk.joint[static_cast<size_t>(thigh)] - sk.joint[kPelvis]);
    const Vector3d ankle = feet[i].T_world_foot.translation();
    const double dxy =
        (Vector2d(hips_xy.x() + hip_offset.x(), hips_xy.y() + hip_offset.y()) - ankle.head<2>())
            .norm();
    const double reach = 0.995 * leg;
    z = std::min(z, ankle.z() + std::sqrt(std::max(0.0, reach * reach - dxy * dxy)));
  }
  pose[kPelvis] = SE3(R_pelvis, Vector3d(hips_xy.x(), hips_xy.y(), z));
  // The chest turns back against the pelvis (so the shoulders face the path), leaning forward.
  pose[kChest] = Child(sk, pose[kPelvis], kPelvis, kChest,
                       RotZ(6 * kDeg * std::cos(2 * M_PI * phase_l)) * Swing(-4 * kDeg));
  pose[kHead] = Child(sk, pose[kChest], kChest, kHead,
                      RotZ(WrapAngle(heading - yaw) + head_yaw) * Swing(2 * kDeg));
  for (int i = 0; i < 2; ++i) {
    const int thigh = i == 0 ? kThighL : kThighR;
    const Vector3d hip = pose[kPelvis] * (sk.joint[static_cast<size_t>(thigh)] - sk.joint[kPelvis]);
    const SE3& T_foot = feet[i].T_world_foot;
    const Vector3d forward = RotZ(std::atan2(T_foot.rotation().toRotationMatrix()(1, 0),
                                             T_foot.rotation().toRotationMatrix()(0, 0))) *
                             Vector3d::UnitX();
    SE3 T_thigh, T_shin;
    const Vector3d ankle =
        LegIk(hip, T_foot.translation(), forward, sk.thigh, sk.shin, &T_thigh, &T_shin);
    pose[static_cast<size_t>(thigh)] = T_thigh;
    pose[static_cast<size_t>(thigh + 1)] = T_shin;
    pose[static_cast<size_t>(thigh + 2)] = SE3(T_foot.rotation(), ankle);
  }
  // Each arm swings with the opposite leg (forward when the other foot strikes).
  const double flex[2] = {4 * kDeg - 16 * kDeg * std::cos(2 * M_PI * phase_l),
                          4 * kDeg + 16 * kDeg * std::cos(2 * M_PI * phase_l)};
  const double elbow[2] = {18 * kDeg + 0.6 * std::max(0.0, flex[0]),
                           18 * kDeg + 0.6 * std::max(0.0, flex[1])};
  Arms(sk, &pose, flex, elbow, 7 * kDeg);
  return pose;
}

BodyPose SeatedPose(const Skeleton& sk, const Vector2d& seat, double heading, double seat_height,
                    double w) {
  BodyPose pose;
  const Matrix3d R = RotZ(heading);
  pose[kPelvis] = SE3(R, Vector3d(seat.x(), seat.y(), seat_height));
  pose[kChest] =
      Child(sk, pose[kPelvis], kPelvis, kChest, Swing(-(8 * kDeg + 6 * kDeg * std::sin(0.45 * w))));
  pose[kHead] = Child(sk, pose[kChest], kChest, kHead, RotZ(25 * kDeg * std::sin(0.31 * w + 1.0)));
  const Vector3d forward = R * Vector3d::UnitX();
  for (int i = 0; i < 2; ++i) {
    const int thigh = i == 0 ? kThighL : kThighR;
    const Vector3d hip = pose[kPelvis] * (sk.joint[static_cast<size_t>(thigh)] - sk.joint[kPelvis]);
    // Feet on the floor below the knees, which move a little.
    const double reach = sk.thigh * (0.92 + 0.05 * std::sin(0.7 * w + i));
    Vector3d ankle = hip + reach * forward;
    ankle.z() = sk.ankle_height;
    SE3 T_thigh, T_shin;
    ankle = LegIk(hip, ankle, forward, sk.thigh, sk.shin, &T_thigh, &T_shin);
    pose[static_cast<size_t>(thigh)] = T_thigh;
    pose[static_cast<size_t>(thigh + 1)] = T_shin;
    pose[static_cast<size_t>(thigh + 2)] = SE3(R, ankle);
  }
  double flex[2], elbow[2];
  for (int i = 0; i < 2; ++i) {
    const double g = std::sin(1.3 * w + 2.1 * i) * std::sin(0.23 * w + i);
    flex[i] = 35 * kDeg + 15 * kDeg * g;
    elbow[i] = 55 * kDeg + 25 * kDeg * g;
  }
  Arms(sk, &pose, flex, elbow, 8 * kDeg);
  return pose;
}

}  // namespace moslam::synth
