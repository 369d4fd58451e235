// Presets that alias (docs/SYNTH.md, "Aliasing presets"): places that look the same although
// they are not, which is what fools place recognition into false loops (docs/EVALUATION.md,
// "False loops"). A street of identical houses and a corridor of identical doors, each straight
// (no place is visited twice: a closed loop is false) and as a ring that comes back to its start
// (one true loop, among many aliases of it). The houses and doors are copies of one model with
// one set of textures stretched over each face, so any two of them look alike to the pixel; only
// their spacing varies a little, as in real streets and corridors.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "moslam/synth/presets.h"
#include "moslam/synth/scene_builder.h"

namespace moslam::synth::internal {
namespace {

// A path around a rectangle with rounded corners (half sizes a, b of the centreline, corner
// radius r), counter-clockwise from the middle of the bottom side heading +x. Position and
// heading (radians) at arc length s (wrapping around).
struct RoundedRectangle {
  double a, b, r;
  double Perimeter() const { return 4 * (a - r) + 4 * (b - r) + 2 * M_PI * r; }
  // Arc length from s to the nearest corner arc (0 on a corner).
  double ToCorner(double s) const {
    s = std::fmod(s, Perimeter());
    if (s < 0) s += Perimeter();
    const double sx = 2 * (a - r), sy = 2 * (b - r), arc = M_PI / 2 * r;
    double start = sx / 2;                  // corner k spans [start, start + arc]
    double best = Perimeter() + start - s;  // the first corner again, across the start
    for (int k = 0; k < 4; ++k) {
      best = std::min(best, s < start ? start - s : std::max(0.0, s - start - arc));
      start += arc + (k % 2 == 0 ? sy : sx);
    }
    return best;
  }
  void At(double s, Vector2d* p, double* heading) const {
    s = std::fmod(s, Perimeter());
    if (s < 0) s += Perimeter();
    const double sx = 2 * (a - r), sy = 2 * (b - r), arc = M_PI / 2 * r;
    // Sides in order: bottom (from its middle), corner, right, corner, top, corner, left,
    // corner, bottom's first half.
    const double lengths[9] = {sx / 2, arc, sy, arc, sx, arc, sy, arc, sx / 2};
    const Vector2d corners[4] = {
        {a - r, b - r}, {-(a - r), b - r}, {-(a - r), -(b - r)}, {a - r, -(b - r)}};
    int i = 0;
    while (i < 8 && s > lengths[i]) s -= lengths[i++];
    const double h = (i / 2) * M_PI / 2;  // heading of the straight side before corner i / 2
    const Vector2d dir(std::cos(h), std::sin(h));
    if (i % 2 == 0) {  // straight
      Vector2d start;
      switch (i) {
        case 0:
          start = {0, -b};
          break;
        case 2:
          start = {a, -(b - r)};
          break;
        case 4:
          start = {a - r, b};
          break;
        case 6:
          start = {-a, b - r};
          break;
        default:
          start = {-(a - r), -b};
          break;
      }
      *p = start + s * dir;
      *heading = h;
    } else {  // corner (i / 2) turning left by s / r
      const double phi = s / r;
      const Vector2d centre = corners[(i / 2 + 3) % 4];
      const double out = h - M_PI / 2;  // from the corner's centre to the path
      *p = centre + r * Vector2d(std::cos(out + phi), std::sin(out + phi));
      *heading = h + phi;
    }
  }
};

// Textures shared by every copy of a house or a door.
struct Look {
  int facade, door, window, roof, frame, picture;
};

Look PickLook(Builder& b, TextureKind facade) {
  Rng& rng = b.rng();
  const TextureSet& tex = b.textures();
  return {Pick(rng, tex, facade),
          Pick(rng, tex, TextureKind::kWood),
          Pick(rng, tex, TextureKind::kPoster),
          Pick(rng, tex, TextureKind::kHair),
          Pick(rng, tex, TextureKind::kCeiling),
          Pick(rng, tex, TextureKind::kPoster)};
}

// One box of a copied model: no texture shift, so every copy looks the same.
void AddCopy(Builder& b, const SE3& T, const Vector3d& half, int texture, double tile,
             float tint = 1.0f) {
  b.Add(T, half, texture, tile, kBackground, 0, tint);
  b.LastBox().uv_offset = Vector2d::Zero();
}

// A house of width 10 m in its own frame: x along the street, the facade in the plane y = 0
// facing -y, z up. Door, four windows, a roof slab and a step, all stretched textures.
void House(Builder& b, const Look& look, const SE3& T) {
  const double w = 10.0, d = 8.0, h = 7.0;
  AddCopy(b, T * At(0, d / 2, h / 2), {w / 2, d / 2, h / 2}, look.facade, 0.0);
  AddCopy(b, T * At(0, d / 2, h + 0.15), {w / 2 + 0.3, d / 2 + 0.3, 0.15}, look.roof, 0.0);
  AddCopy(b, T * At(-2.5, -0.06, 1.1), {0.6, 0.06, 1.1}, look.door, 0.0);
  AddCopy(b, T * At(-2.5, -0.4, 0.08), {1.0, 0.4, 0.08}, look.frame, 0.0, 0.8f);
  for (int i = 0; i < 4; ++i) {
    const double x = i < 2 ? 1.0 + 2.5 * i : -3.0 + 2.5 * (i - 2), z = i < 2 ? 1.6 : 4.6;
    AddCopy(b, T * At(x, -0.05, z), {0.7, 0.05, 0.8}, look.window, 0.0, 0.9f);
  }
}

// A row of houses along the local x axis of T from x0 to x1, on the side +y of it at `offset`
// (the facades face the street), 1-3 m apart.
void HouseRow(Builder& b, const Look& look, const SE3& T, double x0, double x1, double offset) {
  for (double x = x0 + 5.0; x + 5.0 <= x1; x += 10.0 + b.rng().Uniform(1.0, 3.0)) {
    House(b, look, T * At(x, offset, 0));
  }
}

// Road (tiled) over [x0, x1] and pavements over [p0, p1] along the local x axis of T.
void Road(Builder& b, int road, int pavement, const SE3& T, double x0, double x1, double p0,
          double p1) {
  b.Add(T * At((x0 + x1) / 2, 0, -0.1), {(x1 - x0) / 2, 5.0, 0.1}, road, 3.0, kBackground, 0);
  for (int side = -1; side <= 1; side += 2) {
    b.Add(T * At((p0 + p1) / 2, side * 7.0, 0.0), {(p1 - p0) / 2, 2.0, 0.12}, pavement, 1.5,
          kBackground, 0);
  }
}

// The houses' side of both presets: a street along the local x axis of T, houses on its +y
// side over [x0, x1] and on its -y side over [y0, y1], lamp posts on both sides over [x0, x1].
void Street(Builder& b, const Look& look, int post, const SE3& T, double x0, double x1, double y0,
            double y1) {
  HouseRow(b, look, T, x0, x1, 9.0);
  HouseRow(b, look, T * At(0, 0, 0, M_PI), -y1, -y0, 9.0);
  // Posts along [x0, x1] only: the -y side's houses of a ring run round the corners, where a
  // post would stand in the road the car turns into.
  for (double x = x0 + 4.0; x < x1; x += 12.0) {
    for (int side = -1; side <= 1; side += 2) {
      AddCopy(b, T * At(x, side * 6.0, 2.0), {0.08, 0.08, 2.0}, post, 0.5);
    }
  }
}

void StreetPreset(const std::string& name, Builder& b, SequenceSpec* spec, int width, int height) {
  Rng& rng = b.rng();
  const TextureSet& tex = b.textures();
  spec->camera = KittiCamera(width > 0 ? width : 1226, height > 0 ? height : 370);
  spec->baseline_m = 0.537;
  spec->lighting.direction_world = Vector3d(0.3, 0.5, -0.8);
  spec->lighting.ambient = 0.6f;
  const Look look = PickLook(b, TextureKind::kFacade);
  const int road = Pick(rng, tex, TextureKind::kRoad), pave = Pick(rng, tex, TextureKind::kFloor);
  const int post = Pick(rng, tex, TextureKind::kHair);
  const double speed = rng.Uniform(7, 9), lane = -2.2;
  std::array<Wobble, 2> sway = {Wobble(rng, 0.05, 4, 8), Wobble(rng, 0.02, 3, 6)};
  if (name == "street_repeat") {  // 330 m straight along +x
    Road(b, road, pave, SE3(), -20, 330, -20, 330);
    Street(b, look, post, SE3(), -20, 330, -20, 330);
    spec->T_world_cam = [speed, lane, sway](double t) {
      const Vector3d eye(speed * t, lane + sway[0](t), 1.65);
      return Rotate(LookAt(eye, eye + Vector3d(10, 0, -0.3)), 0, sway[1](t), 0);
    };
    return;
  }
  // street_repeat_loop: once around a 110 x 70 m block (corner radius 12 m) and on, slowing
  // down to 4 m/s for the corners as a driver does (over 20 m before and after each). A ground
  // plane shows where the roads and pavements of two sides meet at a corner.
  const RoundedRectangle ring{55.0, 35.0, 12.0};
  b.Add(At(0, 0, -0.35), {ring.a + 30, ring.b + 30, 0.1}, pave, 2.0, kBackground, 0, 0.8f);
  const double sides[4][2] = {
      {ring.a, ring.b}, {ring.b, ring.a}, {ring.a, ring.b}, {ring.b, ring.a}};
  for (int k = 0; k < 4; ++k) {
    // Side k runs along heading k * 90 degrees at distance sides[k][1] from the block's centre.
    const double h = k * M_PI / 2, len = sides[k][0] - ring.r, off = sides[k][1];
    const SE3 T = At(off * std::sin(h), -off * std::cos(h), 0, h);
    // The long sides' roads and pavements run through the corners; the short sides' stop at
    // them, so that no two coplanar boxes overlap (they would flicker between frames).
    const double end = len + ring.r;
    if (k % 2 == 0) {
      Road(b, road, pave, T, -end - 5.0, end + 5.0, -end - 5.0, end + 5.0);
    } else {
      Road(b, road, pave, T, -end + 5.0, end - 5.0, -end + 9.0, end - 9.0);
    }
    // Inside the block (+y of T, the ring runs counter-clockwise) the rows stop 8 m short of
    // the corners, where the two sides' houses would meet; outside they run round the corners
    // (the long sides' rows to the corner squares, the short sides' up to them).
    const double outer = k % 2 == 0 ? end + 17.0 : end + 9.0;
    Street(b, look, post, T, -len + 8.0, len - 8.0, -outer, outer);
  }
  // Arc length driven at time t, integrated once (every 10 ms) from the speed along the ring.
  constexpr double kStep = 0.01, kCornerSpeed = 4.0, kRamp = 20.0;
  std::vector<double> driven = {0.0};
  for (int i = 0; i < 200 * 100; ++i) {
    const double ramp = std::min(1.0, ring.ToCorner(driven.back()) / kRamp);
    driven.push_back(driven.back() + kStep * (kCornerSpeed + (speed - kCornerSpeed) * ramp));
  }
  auto arc_at = [driven](double t) {
    const double i = std::clamp(t / kStep, 0.0, static_cast<double>(driven.size() - 2));
    const size_t k = static_cast<size_t>(i);
    return driven[k] + (i - k) * (driven[k + 1] - driven[k]);
  };
  spec->T_world_cam = [ring, arc_at, lane, sway](double t) {
    Vector2d p;
    double heading;
    ring.At(arc_at(t), &p, &heading);
    const Vector2d left(-std::sin(heading), std::cos(heading));
    const Vector2d eye2 = p + (lane + sway[0](t)) * left;  // kitti_cars' lane: y = lane at +x
    const Vector3d eye(eye2.x(), eye2.y(), 1.65);
    const Vector3d ahead(std::cos(heading), std::sin(heading), -0.03);
    return Rotate(LookAt(eye, eye + 10 * ahead), 0, sway[1](t), 0);
  };
}

// A door of a corridor wall in its own frame: x along the wall, the wall in the plane y = 0 facing
// -y (into the corridor), z up. Frame, leaf, handle and a name plate.
void Door(Builder& b, const Look& look, const SE3& T) {
  AddCopy(b, T * At(0, -0.03, 1.05), {0.55, 0.03, 1.05}, look.frame, 0.0, 0.7f);
  AddCopy(b, T * At(0, -0.06, 1.0), {0.45, 0.03, 1.0}, look.door, 0.0);
  AddCopy(b, T * At(0.33, -0.1, 1.0), {0.06, 0.02, 0.02}, look.roof, 0.0);
  AddCopy(b, T * At(0.8, -0.02, 1.5), {0.12, 0.02, 0.08}, look.window, 0.0);
}

// One straight corridor along the local x axis of T over [x0, x1]: floor, ceiling with lights,
// the walls (only where `walls`; a ring's corners are built by its sides) and doors on both sides
// every 3 m (+-0.3 m).
void Corridor(Builder& b, const Look& look, const SE3& T, double x0, double x1, double half_w,
              int floor, int ceiling) {
  const double h = 2.7, c = (x0 + x1) / 2, half = (x1 - x0) / 2;
  b.Add(T * At(c, 0, -0.1), {half, half_w, 0.1}, floor, 1.5, kBackground, 0);
  b.Add(T * At(c, 0, h + 0.1), {half, half_w, 0.1}, ceiling, 1.5, kBackground, 0, 0.9f);
  for (int side = -1; side <= 1; side += 2) {
    const SE3 wall = T * At(0, side * half_w, 0, side > 0 ? 0.0 : M_PI);
    const double s0 = side > 0 ? x0 : -x1, s1 = side > 0 ? x1 : -x0;
    AddCopy(b, wall * At((s0 + s1) / 2, 0.1, h / 2), {(s1 - s0) / 2, 0.1, h / 2}, look.facade, 1.5);
    for (double x = s0 + 1.5; x + 1.0 <= s1; x += 3.0 + b.rng().Uniform(-0.3, 0.3)) {
      Door(b, look, wall * At(x, 0, 0));
      // A copy of one picture between this door and the next.
      if (x + 2.5 <= s1) {
        AddCopy(b, wall * At(x + 1.5, -0.02, 1.45), {0.3, 0.02, 0.22}, look.picture, 0.0);
      }
    }
  }
  for (double x = x0 + 1.5; x < x1; x += 3.0) {
    AddCopy(b, T * At(x, 0, h - 0.03), {0.6, 0.15, 0.03}, look.window, 0.0, 1.2f);
  }
}

void CorridorPreset(const std::string& name, Builder& b, SequenceSpec* spec, int width,
                    int height) {
  Rng& rng = b.rng();
  const TextureSet& tex = b.textures();
  spec->camera = TumCamera(width > 0 ? width : 640, height > 0 ? height : 480);
  // Tiled walls (a floor-kind texture: tiles, planks), as in school and hospital corridors: the
  // plaster of the office walls leaves a camera facing a corridor's end with too few corners.
  const Look look = PickLook(b, TextureKind::kFloor);
  const int floor = Pick(rng, tex, TextureKind::kFloor);
  const int ceiling = Pick(rng, tex, TextureKind::kCeiling);
  const double half_w = 1.2, speed = rng.Uniform(1.1, 1.3);
  std::array<Wobble, 3> pos = {Wobble(rng, 0.03, 3, 6), Wobble(rng, 0.03, 3, 6),
                               Wobble(rng, 1, 4, 8)};
  // Looking ahead and a little to the side, turning slowly from one wall to the other, so that
  // the doors fill much of the view (as a person's camera would).
  auto pose = [pos](const Vector2d& p, double heading, double t) {
    const double look_side = 0.35 * pos[2](t);
    const Vector3d eye(p.x() + pos[0](t), p.y() + pos[1](t), 1.5);
    const Vector3d ahead(std::cos(heading + look_side), std::sin(heading + look_side), -0.1);
    return LookAt(eye, eye + ahead);
  };
  if (name == "corridor") {  // 36 m straight along +x, 30 m walked
    Corridor(b, look, SE3(), -3, 36, half_w, floor, ceiling);
    AddCopy(b, At(-3.1, 0, 1.35), {0.1, half_w, 1.35}, look.facade, 1.5);
    AddCopy(b, At(36.1, 0, 1.35), {0.1, half_w, 1.35}, look.facade, 1.5);
    spec->T_world_cam = [speed, pose](double t) { return pose(Vector2d(speed * t, 0.0), 0.0, t); };
    return;
  }
  // corridor_loop: once around a ring corridor of 14 x 7 m (centreline) and 3 m on.
  const RoundedRectangle ring{7.0, 3.5, 1.0};
  const double sides[4][2] = {
      {ring.a, ring.b}, {ring.b, ring.a}, {ring.a, ring.b}, {ring.b, ring.a}};
  for (int k = 0; k < 4; ++k) {
    const double h = k * M_PI / 2, len = sides[k][0], off = sides[k][1];
    const SE3 T = At(off * std::sin(h), -off * std::cos(h), 0, h);
    // Each side's walls stop where the inner walls meet; at its far end two pieces close the
    // outer corner: its outer wall run on, and the end wall across.
    Corridor(b, look, T, -len + half_w, len - half_w, half_w, floor, ceiling);
    AddCopy(b, T * At(len, -half_w - 0.1, 1.35), {half_w, 0.1, 1.35}, look.facade, 1.5);
    AddCopy(b, T * At(len + half_w + 0.1, 0, 1.35), {0.1, half_w + 0.2, 1.35}, look.facade, 1.5);
    Door(b, look, T * At(len + half_w, -0.4, 0, -M_PI / 2));
    AddCopy(b, T * At(len + half_w - 0.02, 0.6, 1.45), {0.02, 0.3, 0.22}, look.picture, 0.0);
    b.Add(T * At(len, 0, -0.1), {half_w, half_w, 0.1}, floor, 1.5, kBackground, 0);
    b.Add(T * At(len, 0, 2.8), {half_w, half_w, 0.1}, ceiling, 1.5, kBackground, 0, 0.9f);
  }
  // The walker looks at the path 1.5 m ahead, so that at a corner the view turns into the next
  // side before the wall ahead fills it.
  spec->T_world_cam = [ring, speed, pose](double t) {
    Vector2d p, ahead;
    double heading;
    ring.At(speed * t + 1.5, &ahead, &heading);
    ring.At(speed * t, &p, &heading);
    const Vector2d d = ahead - p;
    return pose(p, std::atan2(d.y(), d.x()), t);
  };
}

}  // namespace

bool IsAliasingPreset(const std::string& name) {
  return name == "street_repeat" || name == "street_repeat_loop" || name == "corridor" ||
         name == "corridor_loop";
}

void MakeAliasingPreset(const std::string& name, Builder& b, SequenceSpec* spec, int width,
                        int height) {
  MOSLAM_CHECK(IsAliasingPreset(name)) << name;
  if (name.rfind("street", 0) == 0) {
    StreetPreset(name, b, spec, width, height);
  } else {
    CorridorPreset(name, b, spec, width, height);
  }
}

}  // namespace moslam::synth::internal
