#include "moslam/synth/presets.h"

#include <cmath>

#include <Eigen/Geometry>

#include "moslam/synth/rng.h"
#include "moslam/synth/scene_builder.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::synth {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
using geometry::SE3;
using internal::At;
using internal::Builder;
using internal::kDeg;
using internal::LookAt;
using internal::Pick;
using internal::Rotate;
using internal::Wobble;

// Stream ids that keep the random choices of presets, training scenes and noise apart.
constexpr uint64_t kStreamScene = 11, kStreamTraining = 0x7121A1;

// The office: a 6 x 6 x 2.8 m room, the camera near the south wall (y = -2.4) looking north at a
// desk group where people walk and sit, as in TUM's fr3 walking/sitting sequences.
constexpr double kRoomW = 6.0, kRoomD = 6.0, kRoomH = 2.8;

void BuildOffice(Builder& b, bool walking, bool seated) {
  Rng& rng = b.rng();
  b.Room(kRoomW, kRoomD, kRoomH);
  // Desk group in the middle-back of the room, chairs behind it (the sitters face the camera).
  const double desk_y = 1.0 + rng.Uniform(-0.1, 0.1);
  b.Desk(-0.9, desk_y, 0.0, true);
  b.Desk(0.9, desk_y, 0.0, true);
  b.Chair(-0.9, desk_y + 0.75, -M_PI / 2);
  b.Chair(0.9, desk_y + 0.75, -M_PI / 2);
  b.Desk(-2.4, -0.6, M_PI / 2, rng.Uniform() < 0.5);
  b.Desk(2.4, 0.2, -M_PI / 2, true);
  b.Shelf(At(-kRoomW / 2 + 0.2, 1.6, 0), 1.6, 2.0);
  b.Shelf(At(kRoomW / 2 - 0.2, -1.4, 0, M_PI), 1.4, 1.8);
  b.Shelf(At(0.0, kRoomD / 2 - 0.2, 0, -M_PI / 2), 2.0, 1.9);
  // Boxes on the floor and a cabinet.
  for (int i = 0; i < 4; ++i) {
    const double s = rng.Uniform(0.2, 0.45);
    b.Add(At(rng.Uniform(-2.6, 2.6), rng.Uniform(2.0, 2.6), s, rng.Uniform(0, M_PI)), {s, s, s},
          Pick(rng, b.textures(), TextureKind::kPoster), 0.0, kBackground, 0);
  }
  if (seated) {
    // Two people at the desks facing the camera (-y), as in fr3 sitting_static.
    for (int i = 0; i < 2; ++i) {
      b.AddPerson(Person::Seated(b.Look(), Vector2d(i == 0 ? -0.9 : 0.9, desk_y + 0.7), -M_PI / 2,
                                 0.5, rng.Uniform(0, 100)));
    }
  }
  if (walking) {
    // Two people walking loops that cross in front of the camera at 0.8-1.2 m (covering 20-60 %
    // of the view there), both in the same direction (+x) so that their motion is coherent, and
    // come back 2-3 m away in front of the desks. The loops are narrow (2.2-2.6 m) so that the
    // walkers stay in view most of the time.
    const double near = -1.25 + rng.Uniform(-0.1, 0.1);
    std::vector<Vector2d> a = {{-1.3, near}, {1.3, near + 0.2}, {1.3, 0.4}, {-1.3, 0.4}};
    std::vector<Vector2d> c = {{1.1, -0.2}, {-1.1, -0.3}, {-1.1, -1.4}, {1.1, -1.3}};
    b.AddPerson(Person::Walking(b.Look(), a, rng.Uniform(0.8, 1.1), rng.Uniform(0, 5)));
    b.AddPerson(Person::Walking(b.Look(), c, rng.Uniform(0.7, 1.0), rng.Uniform(0, 5)));
  }
}

// Issue 24's unknown mover: a cart pushed along y ~ -1 (1.3 m in front of the camera) between
// the two side desks, stopping in the middle of the view for 2-3 s (long enough to be mapped as
// static) and beside the view for 1-2 s. Posters on its sides: as much texture as the walls.
void AddPushedCart(Builder& b) {
  Rng& rng = b.rng();
  Cart c;
  const double y = -1.0 + rng.Uniform(-0.1, 0.1), mid = rng.Uniform(-0.15, 0.15);
  c.stops = {{-1.35, y}, {mid, y}, {1.35, y}, {mid, y}};
  c.dwell_s = {rng.Uniform(1, 2), rng.Uniform(2, 3), rng.Uniform(1, 2), rng.Uniform(2, 3)};
  c.max_speed = rng.Uniform(0.6, 0.8);
  c.side = Pick(rng, b.textures(), TextureKind::kPoster);
  c.top = Pick(rng, b.textures(), TextureKind::kWood);
  c.frame = Pick(rng, b.textures(), TextureKind::kHair);
  c.size = Vector3d(rng.Uniform(1.0, 1.2), rng.Uniform(0.6, 0.75), rng.Uniform(0.9, 1.05));
  b.AddCart(c);
}

std::function<SE3(double)> IndoorTrajectory(const std::string& name, Rng& rng) {
  // Sitting: closer, so the seated people are ~2.5 m away as in fr3 sitting_static.
  const double eye_y = name == "s_static" ? -1.0 : -2.3;
  const Vector3d eye(rng.Uniform(-0.2, 0.2), eye_y, 1.45 + rng.Uniform(-0.1, 0.1));
  const Vector3d target(0.0, 1.0, 1.15);
  const SE3 base = LookAt(eye, target);
  std::array<Wobble, 3> pos = {Wobble(rng, 1, 6, 10), Wobble(rng, 1, 6, 10), Wobble(rng, 1, 6, 10)};
  std::array<Wobble, 3> rot = {Wobble(rng, 1, 5, 9), Wobble(rng, 1, 5, 9), Wobble(rng, 1, 5, 9)};
  auto jitter = [pos, rot](double t, double p_amp, double r_amp, const SE3& T) {
    const Vector3d d(pos[0](t) * p_amp, pos[1](t) * p_amp, pos[2](t) * p_amp);
    const SE3 moved(T.rotation(), T.translation() + d);
    return Rotate(moved, rot[0](t) * r_amp, rot[1](t) * r_amp, rot[2](t) * r_amp);
  };
  if (name == "w_xyz" || name == "unknown_mover") {  // along the axes, ~±0.4 m, little rotation
    return [=](double t) { return jitter(t, 0.4, 1.5 * kDeg, base); };
  }
  if (name == "w_static" || name == "s_static") {  // nearly still: mm and sub-degree jitter
    return [=](double t) { return jitter(t, 0.003, 0.25 * kDeg, base); };
  }
  if (name == "w_rpy") {  // rotation about the camera axes, ±25 degrees, a few cm of translation
    return [=](double t) { return jitter(t, 0.03, 25 * kDeg, base); };
  }
  if (name == "w_halfsphere") {  // on a half sphere of 1 m diameter, looking at the room centre
    const Vector3d centre = eye + Vector3d(0, 0.5, 0);
    const double p1 = rng.Uniform(9, 12), p2 = rng.Uniform(6, 8), ph = rng.Uniform(0, 2 * M_PI);
    return [=](double t) {
      const double az = 60 * kDeg * std::sin(2 * M_PI * t / p1 + ph);
      const double el = 30 * kDeg + 30 * kDeg * std::sin(2 * M_PI * t / p2);
      const Vector3d dir(std::sin(az) * std::cos(el), -std::cos(az) * std::cos(el), std::sin(el));
      return LookAt(centre + 0.5 * dir, target);
    };
  }
  if (name == "loop_room") {
    // A walk around a 1 m circle near the middle of the room, looking outwards (slightly down) at
    // the walls, shelves and desks: one lap every 8 s, so the camera revisits the first views
    // after 240 frames and a loop can be closed; 600 frames walk 2.5 laps, long enough for the
    // drift of an uncorrected run to stand well above the depth noise's centimetre floor.
    const Vector3d centre(rng.Uniform(-0.1, 0.1), -0.8 + rng.Uniform(-0.1, 0.1), 1.4);
    const double phase = rng.Uniform(0, 2 * M_PI), lap_s = 8.0, radius = 1.0;
    return [=](double t) {
      const double a = phase + 2 * M_PI * t / lap_s;
      const Vector3d out(std::cos(a), std::sin(a), 0.0);
      const Vector3d eye = centre + radius * out + Vector3d(0, 0, 0.05 * pos[2](t));
      return jitter(t, 0.02, 1.0 * kDeg, LookAt(eye, eye + out + Vector3d(0, 0, -0.2)));
    };
  }
  MOSLAM_CHECK(false) << "no trajectory for " << name;
  return {};
}

// A street along +x: road, pavements, facades on both sides, cars in both lanes and parked.
void BuildStreet(Builder& b) {
  Rng& rng = b.rng();
  const TextureSet& tex = b.textures();
  const double length = 400.0;
  b.Add(At(length / 2 - 20, 0, -0.1), {length / 2 + 20, 5.0, 0.1},
        Pick(rng, tex, TextureKind::kRoad), 3.0, kBackground, 0);
  for (int side = -1; side <= 1; side += 2) {
    b.Add(At(length / 2 - 20, side * 7.0, 0.0), {length / 2 + 20, 2.0, 0.12},
          Pick(rng, tex, TextureKind::kFloor), 1.5, kBackground, 0);
    double x = -20.0;
    while (x < length) {
      const double w = rng.Uniform(8, 20), h = rng.Uniform(6, 18), d = rng.Uniform(6, 10);
      b.Add(At(x + w / 2, side * (9.0 + d / 2), h / 2), {w / 2, d / 2, h / 2},
            Pick(rng, tex, TextureKind::kFacade), rng.Uniform() < 0.5 ? 0.0 : 6.0, kBackground, 0);
      x += w + rng.Uniform(0.0, 2.0);
    }
    // Poles and signs: vertical structure near the road.
    for (double px = 5.0; px < length; px += rng.Uniform(15, 30)) {
      b.Add(At(px, side * 6.0, 1.5), {0.08, 0.08, 1.5}, Pick(rng, tex, TextureKind::kHair), 0.5,
            kBackground, 0);
    }
  }
  auto car = [&](double x, double y, double heading, double speed) {
    Car c;
    c.start = Vector2d(x, y);
    c.heading = heading;
    c.speed = speed;
    c.paint = Pick(rng, tex, TextureKind::kCarPaint);
    c.glass = Pick(rng, tex, TextureKind::kPoster);
    c.tyre = Pick(rng, tex, TextureKind::kHair);
    c.size = Vector3d(rng.Uniform(3.8, 4.8), rng.Uniform(1.7, 1.9), rng.Uniform(1.4, 1.6));
    b.AddCar(c);
  };
  for (int i = 0; i < 4; ++i) car(15 + 25 * i + rng.Uniform(0, 8), -2.2, 0.0, rng.Uniform(9, 12));
  for (int i = 0; i < 6; ++i) car(40 + 40 * i + rng.Uniform(0, 10), 2.2, M_PI, rng.Uniform(8, 12));
  for (int i = 0; i < 8; ++i) {  // parked: movable but not moving
    car(20 + 35 * i + rng.Uniform(0, 10), (i % 2 ? 1 : -1) * 4.3, i % 2 ? M_PI : 0.0, 0.0);
  }
}

// Issue 29's far-field stereo scene: an open road along +x with nothing near it, so that every
// feature is 20-150 m away (disparity 2.5-19 px with KITTI's bf of 380), where a disparity bias of
// a tenth of a pixel is a depth error of 0.5-4 %. Road and verges are tiled coarsely (few corners
// on them); buildings, signs and billboards stand 20-60 m either side of the road, and a far row
// 100-150 m out. A camera in a lane never comes nearer than 20 m to them, and they leave its
// +-41 degree view before they come nearer than about 23 m in depth.
void BuildOpenRoad(Builder& b) {
  Rng& rng = b.rng();
  const TextureSet& tex = b.textures();
  const double length = 800.0;
  b.Add(At(length / 2 - 50, 0, -0.1), {length / 2 + 50, 8.0, 0.1},
        Pick(rng, tex, TextureKind::kRoad), 40.0, kBackground, 0);
  for (int side = -1; side <= 1; side += 2) {
    b.Add(At(length / 2 - 50, side * 108.0, -0.15), {length / 2 + 50, 100.0, 0.1},
          Pick(rng, tex, TextureKind::kFloor), 60.0, kBackground, 0, 0.8f);
    // Near row, 20-60 m out: houses and sheds with facades facing the road.
    for (double x = -20.0; x < length;) {
      const double w = rng.Uniform(6, 20), h = rng.Uniform(4, 14), d = rng.Uniform(6, 12);
      const double y = rng.Uniform(20, 60) + d / 2;
      b.Add(At(x + w / 2, side * y, h / 2), {w / 2, d / 2, h / 2},
            Pick(rng, tex, TextureKind::kFacade), rng.Uniform() < 0.5 ? 0.0 : 6.0, kBackground, 0);
      x += w + rng.Uniform(5, 25);
    }
    // Billboards and signs on posts, 20-30 m out, facing the traffic.
    for (double x = rng.Uniform(0, 30); x < length; x += rng.Uniform(30, 60)) {
      const double y = side * rng.Uniform(20, 30), w = rng.Uniform(3, 8), h = rng.Uniform(2, 4);
      b.Add(At(x, y, 3.0 + h / 2), {0.1, w / 2, h / 2}, Pick(rng, tex, TextureKind::kPoster), 0.0,
            kBackground, 0);
      b.Add(At(x, y, 1.5), {0.15, 0.15, 1.5}, Pick(rng, tex, TextureKind::kHair), 0.5, kBackground,
            0);
    }
    // Far row, 100-150 m out: large buildings.
    for (double x = -50.0; x < length + 100;) {
      const double w = rng.Uniform(20, 50), h = rng.Uniform(15, 40), d = rng.Uniform(15, 30);
      b.Add(At(x + w / 2, side * (rng.Uniform(100, 150) + d / 2), h / 2), {w / 2, d / 2, h / 2},
            Pick(rng, tex, TextureKind::kFacade), 0.0, kBackground, 0);
      x += w + rng.Uniform(5, 30);
    }
  }
}

}  // namespace

const std::vector<PresetInfo>& Presets() {
  static const std::vector<PresetInfo> kPresets = {
      {"w_xyz", "two people walking, camera translating along x, y, z (fr3 walking_xyz)", false,
       859, 30.0},
      {"w_static", "two people walking, camera nearly still (fr3 walking_static)", false, 743,
       30.0},
      {"w_rpy", "two people walking, camera rotating about its axes (fr3 walking_rpy)", false, 910,
       30.0},
      {"w_halfsphere", "two people walking, camera on a 1 m half sphere (fr3 walking_halfsphere)",
       false, 1067, 30.0},
      {"s_static", "two people seated and gesturing, camera nearly still (fr3 sitting_static)",
       false, 707, 30.0},
      {"kitti_cars", "street with moving and parked cars, stereo car driving at ~8 m/s", true, 400,
       10.0},
      {"static_xyz", "w_xyz's room and camera path without people (static-scene reference)", false,
       859, 30.0},
      {"loop_room",
       "the office without people, camera walking a 1 m circle looking outwards, 2.5 laps "
       "(loop closing)",
       false, 600, 30.0},
      {"street_repeat",
       "a straight street of identical houses, 300 m, no place visited twice (false loops)", true,
       360, 10.0},
      {"street_repeat_loop",
       "identical houses around a 110 x 70 m block, driven once around (4 m/s in the corners) "
       "and 40-100 m on (one true loop among aliases)",
       true, 700, 10.0},
      {"corridor", "a straight corridor of identical doors, 30 m walked (false loops)", false, 750,
       30.0},
      {"corridor_loop",
       "a ring corridor of identical doors (14 x 7 m), walked once around and 5-14 m on (one "
       "true loop among aliases)",
       false, 1250, 30.0},
      // Appended last: a preset's random stream is its index here, so the others stay as they were.
      {"unknown_mover",
       "the office without people; a large cart, labelled background (no network knows it), "
       "pushed back and forth 1.3 m in front of the camera, stopping in view; camera as w_xyz "
       "(moving/ holds its mask)",
       false, 900, 30.0},
      {"open_road",
       "stereo car at ~25 m/s on an open road, every feature 20-150 m away (far-field stereo, "
       "issue 29)",
       true, 100, 10.0},
  };
  return kPresets;
}

const PresetInfo& FindPreset(const std::string& name) {
  std::string known;
  for (const PresetInfo& p : Presets()) {
    if (p.name == name) return p;
    known += (known.empty() ? "" : ", ") + p.name;
  }
  ThrowInput("unknown preset '{}' (known: {})", name, known);
}

namespace {
// The intrinsics of a w0 x h0 camera resampled to width x height: focal lengths scale with the
// image, and the principal point is scaled about pixel corners (OpenCV's pixel centres at
// integers), so the same ray hits the same place in the resized image.
camera::PinholeOptions ScaledCamera(double fx, double fy, double cx, double cy, int w0, int h0,
                                    int width, int height) {
  const double s = static_cast<double>(width) / w0, sy = static_cast<double>(height) / h0;
  camera::PinholeOptions c;
  c.fx = fx * s;
  c.fy = fy * sy;
  c.cx = (cx + 0.5) * s - 0.5;
  c.cy = (cy + 0.5) * sy - 0.5;
  c.width = width;
  c.height = height;
  return c;
}
}  // namespace

camera::PinholeOptions TumCamera(int width, int height) {
  return ScaledCamera(535.4, 539.2, 320.1, 247.6, 640, 480, width, height);
}

camera::PinholeOptions KittiCamera(int width, int height) {
  return ScaledCamera(707.0912, 707.0912, 601.8873, 183.1104, 1226, 370, width, height);
}

namespace {

// A stereo car (KITTI's camera and baseline) driving along +x in a lane, with a little sway.
struct Drive {
  double min_speed, max_speed;  // m/s, drawn once
  double lane;                  // metres (y)
  double yaw_sway;              // radians
  double gaze_rise;             // metres: height of the gaze point 10 m ahead over the eye
};
void SetDrivingCamera(const Drive& drive, int width, int height, Rng& rng, SequenceSpec* spec) {
  spec->camera = KittiCamera(width > 0 ? width : 1226, height > 0 ? height : 370);
  spec->baseline_m = 0.537;
  spec->lighting.direction_world = Vector3d(0.3, 0.5, -0.8);
  spec->lighting.ambient = 0.6f;
  const double speed = rng.Uniform(drive.min_speed, drive.max_speed), lane = drive.lane;
  const double gaze_rise = drive.gaze_rise;
  std::array<Wobble, 2> sway = {Wobble(rng, 0.05, 4, 8), Wobble(rng, drive.yaw_sway, 3, 6)};
  spec->T_world_cam = [speed, lane, gaze_rise, sway](double t) {
    const Vector3d eye(speed * t, lane + sway[0](t), 1.65);
    return Rotate(LookAt(eye, eye + Vector3d(10, 0, gaze_rise)), 0, sway[1](t), 0);
  };
}

}  // namespace

SequenceSpec MakePreset(const std::string& name, uint64_t seed, const TextureSet& textures,
                        int width, int height, PeopleStyle people_style) {
  SequenceSpec spec;
  spec.info = FindPreset(name);
  // static_xyz is w_xyz with the people taken out afterwards: the same random stream gives the same
  // room and camera path, so the two differ only by the moving people.
  const bool static_scene = name == "static_xyz";
  const std::string scene_name = static_scene ? "w_xyz" : name;
  Rng rng(seed, kStreamScene + static_cast<uint64_t>(&FindPreset(scene_name) - Presets().data()));
  Builder b(&spec.world, &rng, &textures);
  b.SetPeopleStyle(people_style, seed);
  if (internal::IsAliasingPreset(name)) {
    internal::MakeAliasingPreset(name, b, &spec, width, height);
    return spec;
  }
  if (name == "open_road") {
    BuildOpenRoad(b);
    SetDrivingCamera({24.0, 26.0, -2.0, 0.01, -0.1}, width, height, rng, &spec);
    return spec;
  }
  if (spec.info.stereo) {
    BuildStreet(b);
    SetDrivingCamera({7.0, 9.0, -2.2, 0.02, -0.3}, width, height, rng, &spec);
    return spec;
  }
  spec.camera = TumCamera(width > 0 ? width : 640, height > 0 ? height : 480);
  const bool people = scene_name != "loop_room" && scene_name != "unknown_mover";
  BuildOffice(b, people && scene_name != "s_static", people && scene_name == "s_static");
  if (scene_name == "unknown_mover") AddPushedCart(b);
  spec.T_world_cam = IndoorTrajectory(scene_name, rng);
  if (static_scene) spec.world.actors.clear();
  return spec;
}

SequenceSpec MakeTrainingScene(uint64_t seed, const TextureSet& textures, int width, int height,
                               PeopleStyle people_style) {
  SequenceSpec spec;
  spec.info = {"train", "independent training frame", false, 1, 30.0};
  Rng rng(seed, kStreamTraining);
  Builder b(&spec.world, &rng, &textures);
  b.SetPeopleStyle(people_style, seed ^ 0x7AA1ULL);
  const double w = rng.Uniform(4, 8), d = rng.Uniform(4, 8), h = rng.Uniform(2.4, 3.2);
  b.Room(w, d, h);
  const int desks = rng.Index(4);
  for (int i = 0; i < desks; ++i) {
    const double x = rng.Uniform(-w / 2 + 1, w / 2 - 1), y = rng.Uniform(-d / 2 + 1, d / 2 - 1);
    b.Desk(x, y, rng.Uniform(0, M_PI), rng.Uniform() < 0.6);
  }
  for (int i = rng.Index(4); i > 0; --i) {
    b.Chair(rng.Uniform(-w / 2 + 0.5, w / 2 - 0.5), rng.Uniform(-d / 2 + 0.5, d / 2 - 0.5),
            rng.Uniform(0, 2 * M_PI));
  }
  if (rng.Uniform() < 0.7) b.Shelf(At(-w / 2 + 0.2, rng.Uniform(-1, 1), 0), 1.4, 1.9);
  const int people = rng.Index(4);
  for (int i = 0; i < people; ++i) {
    const Vector2d p(rng.Uniform(-w / 2 + 0.6, w / 2 - 0.6), rng.Uniform(-d / 4, d / 2 - 0.6));
    if (rng.Uniform() < 0.3) {
      b.Chair(p.x(), p.y(), rng.Uniform(0, 2 * M_PI));
      b.AddPerson(Person::Seated(b.Look(), p, rng.Uniform(0, 2 * M_PI), 0.5, rng.Uniform(0, 100)));
    } else {
      const double heading = rng.Uniform(0, 2 * M_PI);
      const Vector2d dir(std::cos(heading), std::sin(heading));
      b.AddPerson(Person::Walking(b.Look(), {p - dir, p + dir}, 1.0, rng.Uniform(0, 4)));
    }
  }
  spec.camera = TumCamera(width, height);
  const Vector3d eye(rng.Uniform(-w / 2 + 0.5, w / 2 - 0.5), -d / 2 + rng.Uniform(0.4, 1.2),
                     rng.Uniform(0.8, 1.9));
  const Vector3d target(rng.Uniform(-w / 4, w / 4), rng.Uniform(0, d / 2), rng.Uniform(0.3, 1.4));
  const SE3 pose = Rotate(LookAt(eye, target), 0, 0, rng.Uniform(-0.2, 0.2));
  spec.T_world_cam = [pose](double) { return pose; };
  return spec;
}

}  // namespace moslam::synth
