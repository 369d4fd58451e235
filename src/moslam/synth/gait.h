// Poses of the skinned bodies of body.h: walking with planted feet, and sitting.
//
// Walking is driven by footprints rather than by joint-angle curves played back: each foot is
// planted at a footprint along the path for the stance phase (60 % of the gait cycle; heel
// strike, foot flat, heel rise and toe off about the ball of the foot), swings to the next
// footprint in the remaining 40 % (Perry & Burnfield, "Gait Analysis: Normal and Pathological
// Function", 2nd ed. 2010, ch. 1-2), and the hip and knee angles follow from two-bone inverse
// kinematics, so stance feet cannot slide and the knee flexes by itself in swing (about 60 degrees,
// as in Winter's normal gait data). The pelvis drops where the stance legs cannot reach (the
// vertical bob), sways over the stance foot and rotates with the leading leg; the arms swing
// against the legs. Stride length grows with height and with the square root of speed (Grieve &
// Gear, "The relationships between length of stride, step frequency, time of swing and speed of
// walking for children and adults", Ergonomics 1966).
#pragma once

#include <functional>

#include <Eigen/Core>

#include "moslam/synth/body.h"

namespace moslam::synth {

// Ground position (world x, y) and heading (radians from +x) at arc length s along a path.
using PathFunction = std::function<void(double s, Eigen::Vector2d* xy, double* heading)>;

// Stride (two steps), metres, of a person of `height_m` walking at `speed` m/s: 1.45 m for 1.75 m
// at 1.3 m/s.
double StrideLength(double height_m, double speed);

// Where a foot is at arc length s: its ankle frame and whether it is in stance.
struct FootPlacement {
  geometry::SE3 T_world_foot;
  bool stance = false;
  double phase = 0.0;  // gait-cycle phase of this foot in [0, 1): 0 heel strike, 0.6 toe off
};
FootPlacement PlaceFoot(const Skeleton& skeleton, const PathFunction& path, double s, double stride,
                        int side);

// The walking body at arc length s along `path` (s grows with time at the walking speed);
// head_yaw turns the head (radians) against the chest.
BodyPose WalkingPose(const Skeleton& skeleton, const PathFunction& path, double s, double stride,
                     double head_yaw);

// Seated on a seat at `seat` (world x, y) of hip height seat_height, facing `heading`, at time
// w (seconds plus the person's phase): sway, head turns and gestures.
BodyPose SeatedPose(const Skeleton& skeleton, const Eigen::Vector2d& seat, double heading,
                    double seat_height, double w);

}  // namespace moslam::synth
