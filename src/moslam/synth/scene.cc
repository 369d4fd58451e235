#include "moslam/synth/scene.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "moslam/synth/gait.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::synth {
namespace {

using Eigen::Vector3d;
using geometry::SE3;

constexpr double kDeg = M_PI / 180.0;

SE3 Translate(double x, double y, double z) {
  return SE3(Eigen::Quaterniond::Identity(), Vector3d(x, y, z));
}
SE3 RotZ(double a) {
  return SE3(Eigen::Quaterniond(Eigen::AngleAxisd(a, Vector3d::UnitZ())), Vector3d::Zero());
}
// Pitch about the figure's lateral axis (y, left): positive swings a hanging limb forward (+x).
SE3 Swing(double a) {
  return SE3(Eigen::Quaterniond(Eigen::AngleAxisd(-a, Vector3d::UnitY())), Vector3d::Zero());
}
SE3 Roll(double a) {
  return SE3(Eigen::Quaterniond(Eigen::AngleAxisd(a, Vector3d::UnitX())), Vector3d::Zero());
}

Box MakeBox(const SE3& T, const Vector3d& half, int texture, double tile, uint16_t instance) {
  Box b;
  b.T_world_box = T;
  b.half = half;
  b.texture = texture;
  b.tile_m = tile;
  b.class_id = kPerson;
  b.instance = instance;
  // Shift the texture per part so that neighbouring parts do not show the same patch.
  b.uv_offset = Eigen::Vector2d(0.37 * (instance % 7) + 1.1 * half.z(), 2.3 * half.x());
  return b;
}

// A limb hanging from joint frame T_joint (its -z is "down the limb").
Box Limb(const SE3& T_joint, double length, double width, double depth, int texture, double tile,
         uint16_t instance) {
  return MakeBox(T_joint * Translate(0, 0, -length / 2), Vector3d(depth / 2, width / 2, length / 2),
                 texture, tile, instance);
}

struct Pose {
  double hip[2] = {0, 0};       // swing of left, right upper leg (rad, + forward)
  double knee[2] = {0, 0};      // bend of the lower legs (rad, + backward)
  double shoulder[2] = {0, 0};  // swing of upper arms
  double elbow[2] = {0, 0};     // bend of the lower arms (rad, + forward)
  double abduct[2] = {0, 0};    // arm raised sideways (rad)
  double bob = 0.0;             // body height offset (m)
  double lean = 0.0;            // torso pitch (rad, + forward)
  double head_yaw = 0.0;
  double hip_height = 0.0;  // 0: standing
};

void AppendFigure(const PersonLook& look, const SE3& T_world_person, const Pose& pose, uint16_t id,
                  std::vector<Box>* boxes) {
  const double s = look.height_m / 1.75;
  const double leg = 0.45 * s, arm_u = 0.3 * s, arm_l = 0.27 * s;
  const double hip_z = pose.hip_height > 0 ? pose.hip_height : 0.93 * s + pose.bob;
  const SE3 T_pelvis = T_world_person * Translate(0, 0, hip_z);
  for (int side = 0; side < 2; ++side) {
    const double y = side == 0 ? 0.1 * s : -0.1 * s;
    const SE3 T_hip = T_pelvis * Translate(0, y, 0) * Swing(pose.hip[side]);
    boxes->push_back(Limb(T_hip, leg, 0.15 * s, 0.17 * s, look.trousers, 0.3, id));
    const SE3 T_knee = T_hip * Translate(0, 0, -leg) * Swing(-pose.knee[side]);
    boxes->push_back(Limb(T_knee, leg, 0.12 * s, 0.13 * s, look.trousers, 0.3, id));
    const SE3 T_ankle = T_knee * Translate(0, 0, -leg) * Swing(pose.knee[side] - pose.hip[side]);
    boxes->push_back(MakeBox(T_ankle * Translate(0.05 * s, 0, -0.04 * s),
                             Vector3d(0.13 * s, 0.055 * s, 0.04 * s), look.shoes, 0.2, id));
  }
  const SE3 T_torso = T_pelvis * Swing(-pose.lean);
  const double torso_h = 0.55 * s;
  boxes->push_back(MakeBox(T_torso * Translate(0, 0, torso_h / 2 + 0.02 * s),
                           Vector3d(0.12 * s, 0.2 * s, torso_h / 2 + 0.02 * s), look.shirt, 0.4,
                           id));
  const SE3 T_neck = T_torso * Translate(0, 0, torso_h) * RotZ(pose.head_yaw);
  boxes->push_back(MakeBox(T_neck * Translate(0, 0, 0.05 * s), Vector3d(0.05, 0.05, 0.05) * s,
                           look.skin, 0.15, id));
  boxes->push_back(MakeBox(T_neck * Translate(0.01 * s, 0, 0.19 * s),
                           Vector3d(0.1, 0.085, 0.12) * s, look.skin, 0.15, id));
  boxes->push_back(MakeBox(T_neck * Translate(-0.02 * s, 0, 0.28 * s),
                           Vector3d(0.1, 0.092, 0.045) * s, look.hair, 0.15, id));
  boxes->push_back(MakeBox(T_neck * Translate(-0.08 * s, 0, 0.2 * s),
                           Vector3d(0.035, 0.092, 0.09) * s, look.hair, 0.15, id));
  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? 1.0 : -1.0;
    const SE3 T_shoulder = T_torso * Translate(0, sign * 0.26 * s, torso_h - 0.04 * s) *
                           Roll(sign * pose.abduct[side]) * Swing(pose.shoulder[side]);
    boxes->push_back(Limb(T_shoulder, arm_u, 0.1 * s, 0.1 * s, look.shirt, 0.4, id));
    const SE3 T_elbow = T_shoulder * Translate(0, 0, -arm_u) * Swing(pose.elbow[side]);
    boxes->push_back(Limb(T_elbow, arm_l, 0.085 * s, 0.085 * s, look.shirt, 0.4, id));
    boxes->push_back(MakeBox(T_elbow * Translate(0, 0, -arm_l - 0.07 * s),
                             Vector3d(0.04, 0.03, 0.07) * s, look.skin, 0.15, id));
  }
}

}  // namespace

const char* ClassName(int class_id) {
  static const char* const kNames[kNumClasses] = {"background", "person",    "car",
                                                  "chair",      "tvmonitor", "diningtable"};
  MOSLAM_CHECK(class_id >= 0 && class_id < kNumClasses) << "class id " << class_id;
  return kNames[class_id];
}

bool IsMovableClass(int class_id) { return class_id == kPerson || class_id == kCar; }

const char* PeopleStyleName(PeopleStyle style) {
  return style == PeopleStyle::kBodies ? "bodies" : "boxes";
}

PeopleStyle ParsePeopleStyle(const std::string& name) {
  if (name == "boxes") return PeopleStyle::kBoxes;
  if (name == "bodies") return PeopleStyle::kBodies;
  throw InputError("people style '" + name + "': expected boxes or bodies");
}

Person Person::Walking(const PersonLook& look, std::vector<Eigen::Vector2d> path, double speed,
                       double start_m) {
  MOSLAM_CHECK(path.size() >= 2 && speed > 0);
  Person p;
  p.look_ = look;
  if (look.body) p.body_ = std::make_shared<const BodyModel>(look.shape);
  p.path_ = std::move(path);
  p.speed_ = speed;
  p.start_m_ = start_m;
  p.cumulative_.push_back(0.0);
  for (size_t i = 0; i < p.path_.size(); ++i) {
    const auto& a = p.path_[i];
    const auto& b = p.path_[(i + 1) % p.path_.size()];
    p.cumulative_.push_back(p.cumulative_.back() + (b - a).norm());
  }
  return p;
}

Person Person::Seated(const PersonLook& look, const Eigen::Vector2d& seat, double heading,
                      double seat_height, double phase) {
  Person p;
  p.look_ = look;
  if (look.body) p.body_ = std::make_shared<const BodyModel>(look.shape);
  p.seated_ = true;
  p.seat_ = seat;
  p.heading_ = heading;
  p.seat_height_ = seat_height;
  p.phase_ = phase;
  return p;
}

void Person::PathAt(double s, Eigen::Vector2d* xy, double* heading) const {
  const double total = cumulative_.back();
  auto at = [&](double s) {
    s = std::fmod(s, total);
    if (s < 0) s += total;
    const size_t i = static_cast<size_t>(
        std::upper_bound(cumulative_.begin(), cumulative_.end(), s) - cumulative_.begin() - 1);
    const size_t k = std::min(i, path_.size() - 1);
    const auto& a = path_[k];
    const auto& b = path_[(k + 1) % path_.size()];
    const double len = cumulative_[k + 1] - cumulative_[k];
    return Eigen::Vector2d(a + (b - a) * (len > 0 ? (s - cumulative_[k]) / len : 0.0));
  };
  // Cut corners: position and heading come from points 0.3 m behind and ahead, so turns are
  // smooth instead of instantaneous.
  const Eigen::Vector2d behind = at(s - 0.3), ahead = at(s + 0.3);
  *xy = 0.5 * (behind + ahead);
  const Eigen::Vector2d d = ahead - behind;
  *heading = std::atan2(d.y(), d.x());
}

void Person::Place(double t, Eigen::Vector2d* xy, double* heading) const {
  if (seated_) {
    *xy = seat_;
    *heading = heading_;
    return;
  }
  PathAt(start_m_ + speed_ * t, xy, heading);
}

BodyPose Person::PoseAt(double t) const {
  MOSLAM_CHECK(body_ != nullptr);
  const Skeleton& sk = body_->skeleton();
  if (seated_) return SeatedPose(sk, seat_, heading_, seat_height_, phase_ + t);
  const PathFunction path = [this](double s, Eigen::Vector2d* xy, double* heading) {
    PathAt(s, xy, heading);
  };
  return WalkingPose(sk, path, start_m_ + speed_ * t, StrideLength(look_.shape.height_m, speed_),
                     10 * kDeg * std::sin(0.4 * t + start_m_));
}

void Person::AppendMeshes(double t, uint16_t instance, std::vector<Mesh>* meshes) const {
  if (body_) meshes->push_back(body_->Skin(PoseAt(t), kPerson, instance));
}

void Person::AppendBoxes(double t, uint16_t instance, std::vector<Box>* boxes) const {
  if (body_) return;
  Eigen::Vector2d xy;
  double heading = 0.0;
  Place(t, &xy, &heading);
  Pose pose;
  if (seated_) {
    // Seated: thighs forward, shins down, small sway, head turns, forearms gesture.
    const double w = phase_ + t;
    pose.hip_height = seat_height_;
    pose.hip[0] = pose.hip[1] = 88 * kDeg;
    pose.knee[0] = pose.knee[1] = 88 * kDeg + 4 * kDeg * std::sin(0.7 * w);
    pose.lean = 8 * kDeg + 6 * kDeg * std::sin(0.45 * w);
    pose.head_yaw = 25 * kDeg * std::sin(0.31 * w + 1.0);
    for (int side = 0; side < 2; ++side) {
      const double g = std::sin(1.3 * w + 2.1 * side) * std::sin(0.23 * w + side);
      pose.shoulder[side] = 35 * kDeg + 15 * kDeg * g;
      pose.elbow[side] = 55 * kDeg + 25 * kDeg * g;
      pose.abduct[side] = 8 * kDeg;
    }
  } else {
    // Gait: one cycle per ~1.4 m (two steps of 0.7 m); hip +-25 deg, knee up to 35 deg, arms
    // swinging against the legs (textbook normal-gait amplitudes).
    const double phase = 2.0 * M_PI * (start_m_ + speed_ * t) / 1.4;
    const double sp = std::sin(phase);
    pose.hip[0] = 25 * kDeg * sp;
    pose.hip[1] = -pose.hip[0];
    pose.knee[0] = 5 * kDeg + 30 * kDeg * std::max(0.0, -std::cos(phase));
    pose.knee[1] = 5 * kDeg + 30 * kDeg * std::max(0.0, std::cos(phase));
    pose.shoulder[0] = -22 * kDeg * sp;
    pose.shoulder[1] = 22 * kDeg * sp;
    pose.elbow[0] = 15 * kDeg + 10 * kDeg * std::max(0.0, -sp);
    pose.elbow[1] = 15 * kDeg + 10 * kDeg * std::max(0.0, sp);
    pose.abduct[0] = pose.abduct[1] = 5 * kDeg;
    pose.bob = 0.025 * std::abs(std::cos(phase));
    pose.lean = 4 * kDeg;
    pose.head_yaw = 10 * kDeg * std::sin(0.4 * t + start_m_);
  }
  const SE3 T_world_person = Translate(xy.x(), xy.y(), 0.0) * RotZ(heading);
  AppendFigure(look_, T_world_person, pose, instance, boxes);
}

void Car::AppendBoxes(double t, uint16_t instance, std::vector<Box>* boxes) const {
  const Eigen::Vector2d xy =
      start + speed * t * Eigen::Vector2d(std::cos(heading), std::sin(heading));
  const SE3 T = Translate(xy.x(), xy.y(), 0.0) * RotZ(heading);
  const double l = size.x(), w = size.y(), h = size.z();
  auto add = [&](const SE3& pose, const Vector3d& half, int texture, double tile, float tint) {
    Box b = MakeBox(pose, half, texture, tile, instance);
    b.class_id = kCar;
    b.tint = tint;
    boxes->push_back(b);
  };
  add(T * Translate(0, 0, 0.3 + 0.27 * h), Vector3d(l / 2, w / 2, 0.27 * h), paint, 1.0, 1.0f);
  add(T * Translate(-0.08 * l, 0, 0.3 + 0.74 * h), Vector3d(0.27 * l, 0.45 * w, 0.2 * h), glass,
      0.0, 0.6f);
  add(T * Translate(-0.08 * l, 0, 0.3 + 0.95 * h), Vector3d(0.25 * l, 0.43 * w, 0.012 * h), paint,
      1.0, 1.0f);
  const double wheel_angle = speed * t / 0.32;  // rolling wheels
  for (int i = 0; i < 4; ++i) {
    const double x = (i < 2 ? 0.32 : -0.32) * l, y = (i % 2 == 0 ? 0.5 : -0.5) * w;
    const SE3 spin(Eigen::Quaterniond(Eigen::AngleAxisd(wheel_angle, Vector3d::UnitY())),
                   Vector3d::Zero());
    add(T * Translate(x, y, 0.32) * spin, Vector3d(0.3, 0.1, 0.3), tyre, 0.3, 0.5f);
  }
}

Eigen::Vector2d Cart::PositionAt(double t) const {
  MOSLAM_CHECK(!stops.empty() && dwell_s.size() == stops.size() && max_speed > 0.0);
  // One cycle: per stop, its dwell, then the leg to the next stop. A leg of length L with the
  // speed profile v(u) = v_max sin(pi u / T) takes T = pi L / (2 v_max).
  const size_t n = stops.size();
  std::vector<double> leg_s(n);
  double cycle = 0.0;
  for (size_t i = 0; i < n; ++i) {
    leg_s[i] = M_PI * (stops[(i + 1) % n] - stops[i]).norm() / (2.0 * max_speed);
    cycle += dwell_s[i] + leg_s[i];
  }
  if (cycle <= 0.0) return stops.front();
  double u = std::fmod(std::max(t, 0.0), cycle);
  for (size_t i = 0; i < n; ++i) {
    if (u < dwell_s[i]) return stops[i];
    u -= dwell_s[i];
    if (u < leg_s[i]) {
      const double f = 0.5 * (1.0 - std::cos(M_PI * u / leg_s[i]));  // 0 -> 1, smooth ends
      return stops[i] + f * (stops[(i + 1) % n] - stops[i]);
    }
    u -= leg_s[i];
  }
  return stops.front();
}

void Cart::AppendBoxes(double t, uint16_t instance, std::vector<Box>* boxes) const {
  const Eigen::Vector2d xy = PositionAt(t);
  const SE3 T = Translate(xy.x(), xy.y(), 0.0) * RotZ(heading);
  const double l = size.x(), w = size.y(), h = size.z(), castor = 0.12;
  auto add = [&](const SE3& pose, const Vector3d& half, int texture, double tile, float tint) {
    Box b = MakeBox(pose, half, texture, tile, instance);
    b.class_id = kBackground;  // unknown to every model card: that is the point of it
    b.tint = tint;
    boxes->push_back(b);
  };
  add(T * Translate(0, 0, castor + h / 2), Vector3d(l / 2, w / 2, h / 2), side, 0.0, 1.0f);
  add(T * Translate(0, 0, castor + h + 0.01), Vector3d(l / 2 + 0.02, w / 2 + 0.02, 0.01), top, 0.6,
      0.9f);
  // Push handle at one end: two posts and a bar.
  for (int s = -1; s <= 1; s += 2) {
    add(T * Translate(-l / 2 - 0.03, s * (w / 2 - 0.05), castor + h + 0.12),
        Vector3d(0.015, 0.015, 0.12), frame, 0.3, 0.5f);
  }
  add(T * Translate(-l / 2 - 0.03, 0, castor + h + 0.24), Vector3d(0.015, w / 2 - 0.03, 0.015),
      frame, 0.3, 0.5f);
  for (int i = 0; i < 4; ++i) {  // castors
    const double x = (i < 2 ? 1 : -1) * (l / 2 - 0.08), y = (i % 2 ? 1 : -1) * (w / 2 - 0.08);
    add(T * Translate(x, y, castor / 2), Vector3d(0.05, 0.03, castor / 2), frame, 0.3, 0.4f);
  }
}

void Actor::AppendBoxes(double t, std::vector<Box>* boxes) const {
  switch (kind) {
    case ActorKind::kPerson:
      person.AppendBoxes(t, instance, boxes);
      break;
    case ActorKind::kCar:
      car.AppendBoxes(t, instance, boxes);
      break;
    case ActorKind::kCart:
      cart.AppendBoxes(t, instance, boxes);
      break;
  }
}

void Actor::AppendMeshes(double t, std::vector<Mesh>* meshes) const {
  if (kind == ActorKind::kPerson) person.AppendMeshes(t, instance, meshes);
}

std::vector<Mesh> World::MeshesAt(double t) const {
  std::vector<Mesh> meshes;
  for (const Actor& a : actors) a.AppendMeshes(t, &meshes);
  return meshes;
}

std::vector<Box> World::BoxesAt(double t) const {
  std::vector<Box> boxes = static_boxes;
  for (const Actor& a : actors) a.AppendBoxes(t, &boxes);
  return boxes;
}

std::vector<uint16_t> World::MovingInstances(double t, double dt) const {
  std::vector<uint16_t> moving;
  for (const Actor& a : actors) {
    std::vector<Box> now, before;
    a.AppendBoxes(t, &now);
    a.AppendBoxes(t - dt, &before);
    double max_shift = 0.0;
    for (size_t i = 0; i < now.size() && i < before.size(); ++i) {
      for (int c = 0; c < 8; ++c) {
        const Vector3d corner((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1);
        const Vector3d local = corner.cwiseProduct(now[i].half);
        max_shift = std::max(max_shift,
                             (now[i].T_world_box * local - before[i].T_world_box * local).norm());
      }
    }
    std::vector<Mesh> mesh_now, mesh_before;
    a.AppendMeshes(t, &mesh_now);
    a.AppendMeshes(t - dt, &mesh_before);
    for (size_t m = 0; m < mesh_now.size() && m < mesh_before.size(); ++m) {
      const auto& vn = mesh_now[m].vertices;
      const auto& vb = mesh_before[m].vertices;
      for (size_t i = 0; i < vn.size() && i < vb.size(); ++i) {
        max_shift = std::max(max_shift, static_cast<double>((vn[i].p - vb[i].p).norm()));
      }
    }
    if (max_shift > 5e-4) moving.push_back(a.instance);
  }
  return moving;
}

}  // namespace moslam::synth
