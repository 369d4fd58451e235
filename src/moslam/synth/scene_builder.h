// The building blocks of the presets (presets.cc, presets_aliasing.cc): poses, texture picks,
// a look-at camera, smooth hand-held wobble, and Builder, which adds boxes, rooms, furniture,
// people and cars to a World. Internal to the synth module.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "moslam/geometry/se3.h"
#include "moslam/synth/presets.h"
#include "moslam/synth/rng.h"
#include "moslam/synth/scene.h"
#include "moslam/synth/texture.h"
#include "moslam/util/check.h"

namespace moslam::synth::internal {

using Eigen::Vector2d;
using Eigen::Vector3d;
using geometry::SE3;

constexpr double kDeg = M_PI / 180.0;

inline SE3 At(double x, double y, double z, double yaw = 0.0) {
  return SE3(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Vector3d::UnitZ())), Vector3d(x, y, z));
}

inline int Pick(Rng& rng, const TextureSet& set, TextureKind kind) {
  const auto& list = set.OfKind(kind);
  MOSLAM_CHECK(!list.empty()) << "no texture of kind " << static_cast<int>(kind);
  return list[static_cast<size_t>(rng.Index(static_cast<int>(list.size())))];
}

// Camera looking from `eye` at `target`, world z up: OpenCV axes (x right, y down, z forward).
inline SE3 LookAt(const Vector3d& eye, const Vector3d& target) {
  const Vector3d z = (target - eye).normalized();
  const Vector3d x = z.cross(Vector3d::UnitZ()).normalized();
  const Vector3d y = z.cross(x);
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = z;
  return SE3(R, eye);
}

class Builder {
 public:
  Builder(World* world, Rng* rng, const TextureSet* textures)
      : world_(*world), rng_(*rng), tex_(*textures) {}

  uint16_t NewInstance() { return world_.next_instance++; }

  void Add(const SE3& T, const Vector3d& half, int texture, double tile, uint8_t cls,
           uint16_t instance, float tint = 1.0f) {
    Box b;
    b.T_world_box = T;
    b.half = half;
    b.texture = texture;
    b.tile_m = tile;
    b.class_id = cls;
    b.instance = instance;
    b.tint = tint;
    b.uv_offset = Vector2d(rng_.Uniform(), rng_.Uniform());
    world_.static_boxes.push_back(b);
  }

  // Walls, floor and ceiling of a room [-w/2, w/2] x [-d/2, d/2] x [0, h], seen from inside.
  void Room(double w, double d, double h) {
    const int wall = Pick(rng_, tex_, TextureKind::kWall);
    const int wall2 = Pick(rng_, tex_, TextureKind::kWall);
    const double t = 0.1;
    Add(At(0, 0, -t), {w / 2 + t, d / 2 + t, t}, Pick(rng_, tex_, TextureKind::kFloor), 1.2,
        kBackground, 0);
    Add(At(0, 0, h + t), {w / 2 + t, d / 2 + t, t}, Pick(rng_, tex_, TextureKind::kCeiling), 1.5,
        kBackground, 0, 0.9f);
    Add(At(0, d / 2 + t, h / 2), {w / 2, t, h / 2}, wall, 1.6, kBackground, 0);
    Add(At(0, -d / 2 - t, h / 2), {w / 2, t, h / 2}, wall, 1.6, kBackground, 0);
    Add(At(w / 2 + t, 0, h / 2), {t, d / 2, h / 2}, wall2, 1.6, kBackground, 0, 0.95f);
    Add(At(-w / 2 - t, 0, h / 2), {t, d / 2, h / 2}, wall2, 1.6, kBackground, 0, 0.95f);
    // Posters and boards along the walls (a lab is cluttered: TUM's fr3 office has many).
    for (int i = 0; i < 10; ++i) {
      const int side = i % 4;
      const double pw = rng_.Uniform(0.4, 1.1), ph = rng_.Uniform(0.4, 0.9);
      const double z = rng_.Uniform(1.0, h - 0.6);
      const double along = rng_.Uniform(-0.4, 0.4);
      const int poster = Pick(rng_, tex_, TextureKind::kPoster);
      if (side < 2) {
        const double y = side == 0 ? d / 2 - 0.01 : -d / 2 + 0.01;
        Add(At(along * w, y, z), {pw / 2, 0.008, ph / 2}, poster, 0.0, kBackground, 0);
      } else {
        const double x = side == 2 ? w / 2 - 0.01 : -w / 2 + 0.01;
        Add(At(x, along * d, z), {0.008, pw / 2, ph / 2}, poster, 0.0, kBackground, 0);
      }
    }
  }

  // A desk (diningtable) at (x, y) with yaw, and optionally a monitor on it.
  void Desk(double x, double y, double yaw, bool monitor) {
    const uint16_t id = NewInstance();
    const int wood = Pick(rng_, tex_, TextureKind::kWood);
    const double l = rng_.Uniform(1.2, 1.8), dd = rng_.Uniform(0.7, 0.9), hh = 0.74;
    const SE3 T = At(x, y, 0, yaw);
    Add(T * At(0, 0, hh - 0.02), {l / 2, dd / 2, 0.02}, wood, 0.8, kDiningTable, id);
    for (int i = 0; i < 4; ++i) {
      const double lx = (i < 2 ? 1 : -1) * (l / 2 - 0.05), ly = (i % 2 ? 1 : -1) * (dd / 2 - 0.05);
      Add(T * At(lx, ly, (hh - 0.04) / 2), {0.03, 0.03, (hh - 0.04) / 2}, wood, 0.5, kDiningTable,
          id, 0.7f);
    }
    // Clutter on the desk: books and boxes (background).
    for (int i = 0; i < 3; ++i) {
      Add(T * At(rng_.Uniform(-l / 2 + 0.2, l / 2 - 0.2), rng_.Uniform(-dd / 4, dd / 4), hh + 0.04,
                 rng_.Uniform(0, M_PI)),
          {rng_.Uniform(0.08, 0.18), rng_.Uniform(0.06, 0.12), 0.04},
          Pick(rng_, tex_, TextureKind::kPoster), 0.0, kBackground, 0);
    }
    if (monitor) {
      const uint16_t mid = NewInstance();
      const double mw = rng_.Uniform(0.45, 0.6), mh = mw * 0.62;
      const SE3 Tm = T * At(rng_.Uniform(-0.2, 0.2), dd / 2 - 0.2, hh, rng_.Uniform(-0.2, 0.2));
      Add(Tm * At(0, 0, 0.12 + mh / 2), {mw / 2, 0.025, mh / 2},
          Pick(rng_, tex_, TextureKind::kPoster), 0.0, kTvMonitor, mid);
      Add(Tm * At(0, 0.02, 0.06), {0.03, 0.02, 0.06}, Pick(rng_, tex_, TextureKind::kHair), 0.2,
          kTvMonitor, mid, 0.5f);
      Add(Tm * At(0, 0.02, 0.005), {0.12, 0.08, 0.005}, Pick(rng_, tex_, TextureKind::kHair), 0.2,
          kTvMonitor, mid, 0.5f);
    }
  }

  // A chair at (x, y) facing yaw (its seat's front points along yaw).
  void Chair(double x, double y, double yaw) {
    const uint16_t id = NewInstance();
    const int fabric = Pick(rng_, tex_, TextureKind::kTrousers);
    const SE3 T = At(x, y, 0, yaw);
    Add(T * At(0, 0, 0.45), {0.23, 0.23, 0.03}, fabric, 0.3, kChair, id);
    Add(T * At(-0.22, 0, 0.75), {0.03, 0.22, 0.27}, fabric, 0.3, kChair, id);
    Add(T * At(0, 0, 0.22), {0.03, 0.03, 0.21}, fabric, 0.3, kChair, id, 0.4f);
    Add(T * At(0, 0, 0.02), {0.28, 0.05, 0.02}, fabric, 0.3, kChair, id, 0.4f);
    Add(T * At(0, 0, 0.02), {0.05, 0.28, 0.02}, fabric, 0.3, kChair, id, 0.4f);
  }

  // A shelf of books against a wall (background class).
  void Shelf(const SE3& T, double width, double height) {
    const int wood = Pick(rng_, tex_, TextureKind::kWood);
    const double depth = 0.35;
    Add(T * At(0, 0, height / 2), {depth / 2, width / 2, 0.02}, wood, 0.6, kBackground, 0);
    const int levels = 4;
    for (int i = 0; i <= levels; ++i) {
      const double z = i * height / levels;
      Add(T * At(0, 0, z + 0.01), {depth / 2, width / 2, 0.015}, wood, 0.6, kBackground, 0);
      if (i == levels) break;
      double yy = -width / 2 + 0.03;
      while (yy < width / 2 - 0.05) {
        const double bw = rng_.Uniform(0.025, 0.07),
                     bh = rng_.Uniform(0.18, height / levels - 0.04);
        Add(T * At(0, yy + bw / 2, z + 0.025 + bh / 2), {depth / 2 - 0.04, bw / 2, bh / 2},
            Pick(rng_, tex_, TextureKind::kPoster), 0.0, kBackground, 0,
            static_cast<float>(rng_.Uniform(0.6, 1.1)));
        yy += bw + 0.004;
      }
    }
    Add(T * At(depth / 2 - 0.01, -width / 2, height / 2), {depth / 2, 0.015, height / 2}, wood, 0.6,
        kBackground, 0);
    Add(T * At(depth / 2 - 0.01, width / 2, height / 2), {depth / 2, 0.015, height / 2}, wood, 0.6,
        kBackground, 0);
  }

  // How Look() dresses people; bodies draw their shapes from a stream of their own, so a preset
  // has the same room, paths and camera with either style.
  void SetPeopleStyle(PeopleStyle style, uint64_t seed) {
    style_ = style;
    body_rng_ = Rng(seed, 0xB0D1E5ULL);
  }

  PersonLook Look() {
    PersonLook look;
    look.shirt = Pick(rng_, tex_, TextureKind::kClothing);
    look.trousers = Pick(rng_, tex_, TextureKind::kTrousers);
    look.skin = Pick(rng_, tex_, TextureKind::kSkin);
    look.hair = Pick(rng_, tex_, TextureKind::kHair);
    look.shoes = Pick(rng_, tex_, TextureKind::kHair);
    look.height_m = rng_.Uniform(1.6, 1.9);
    if (style_ == PeopleStyle::kBodies) look = BodyLook(look);
    return look;
  }

  // A procedural texture of a kind (never a photograph), from the body stream.
  int ProceduralPick(Rng& r, TextureKind kind) const {
    std::vector<int> list;
    for (int i : tex_.OfKind(kind)) {
      if (tex_.textures()[static_cast<size_t>(i)].name.rfind("procedural:", 0) == 0) {
        list.push_back(i);
      }
    }
    if (list.empty()) return -1;
    return list[static_cast<size_t>(r.Index(static_cast<int>(list.size())))];
  }

  // A body of anthropometric proportions (heights of adults: about N(1.77, 0.07) m for men and
  // N(1.63, 0.07) m for women, cut to 1.5-1.95 m), a skin tone from light to dark, hair, clothes.
  PersonLook BodyLook(PersonLook look) {
    Rng& r = body_rng_;
    BodyShape& b = look.shape;
    look.body = true;
    b.female = r.Uniform() < 0.5;
    b.height_m = std::clamp(r.Normal(b.female ? 1.63 : 1.77, 0.07), 1.5, 1.95);
    look.height_m = b.height_m;
    b.build = std::clamp(r.Normal(0.45, 0.25), 0.0, 1.0);
    static const float kSkin[6][3] = {{0.96f, 0.8f, 0.69f},  {0.92f, 0.72f, 0.58f},
                                      {0.8f, 0.6f, 0.45f},   {0.66f, 0.46f, 0.32f},
                                      {0.48f, 0.32f, 0.22f}, {0.33f, 0.22f, 0.15f}};
    static const float kHair[6][3] = {{0.06f, 0.05f, 0.045f}, {0.18f, 0.12f, 0.08f},
                                      {0.35f, 0.23f, 0.13f},  {0.72f, 0.58f, 0.36f},
                                      {0.55f, 0.53f, 0.5f},   {0.5f, 0.22f, 0.1f}};
    const auto* skin = kSkin[r.Index(6)];
    const auto* hair = kHair[r.Uniform() < 0.45 ? 0 : r.Index(6)];
    b.skin = Eigen::Vector3f(skin[0], skin[1], skin[2]);
    b.hair = Eigen::Vector3f(hair[0], hair[1], hair[2]);
    b.long_hair = r.Uniform() < (b.female ? 0.7 : 0.08);
    b.skirt = b.female && r.Uniform() < 0.35;
    b.short_sleeves = r.Uniform() < 0.4;
    // Clothes as people wear them: plain colours or the procedural cloth patterns (plaid,
    // stripes, weave) in garment colours; photographs (street scenes) make no shirt.
    static const float kGarment[10][3] = {
        {0.92f, 0.92f, 0.9f},  {0.1f, 0.1f, 0.11f},  {0.15f, 0.2f, 0.38f},  {0.5f, 0.5f, 0.52f},
        {0.62f, 0.12f, 0.12f}, {0.2f, 0.38f, 0.24f}, {0.76f, 0.68f, 0.52f}, {0.5f, 0.65f, 0.85f},
        {0.85f, 0.55f, 0.2f},  {0.45f, 0.25f, 0.45f}};
    static const float kLegwear[5][3] = {{0.18f, 0.25f, 0.42f},
                                         {0.1f, 0.1f, 0.1f},
                                         {0.4f, 0.4f, 0.42f},
                                         {0.6f, 0.52f, 0.38f},
                                         {0.28f, 0.22f, 0.16f}};
    auto colour = [](const float* c, Rng& rng) {
      const float k = static_cast<float>(rng.Uniform(0.85, 1.1));
      return Eigen::Vector3f(std::min(1.f, c[0] * k), std::min(1.f, c[1] * k),
                             std::min(1.f, c[2] * k));
    };
    const float* shirt = kGarment[r.Index(10)];
    b.shirt_colour = colour(shirt, r);
    b.shirt = r.Uniform() < 0.7 ? -2 : ProceduralPick(r, TextureKind::kClothing);
    // A pattern keeps a little of the garment colour: the procedural prints are loud.
    if (b.shirt >= 0) b.shirt_colour = b.shirt_colour * 0.3f + Eigen::Vector3f::Constant(0.6f);
    const float* legs = kLegwear[r.Index(5)];
    b.trousers_colour = colour(legs, r);
    b.trousers = r.Uniform() < 0.6 ? ProceduralPick(r, TextureKind::kTrousers) : -2;
    if (b.trousers >= 0) {
      b.trousers_colour = b.trousers_colour * 0.6f + Eigen::Vector3f::Constant(0.5f);
    }
    if (b.skirt) b.trousers_colour = colour(kGarment[r.Index(10)], r);
    b.shoes = -1;
    b.shoes_colour = Eigen::Vector3f::Constant(static_cast<float>(r.Uniform(0.05, 0.3)));
    return look;
  }

  void AddPerson(const Person& p) {
    Actor a;
    a.kind = ActorKind::kPerson;
    a.person = p;
    AddActor(std::move(a));
  }

  void AddCar(const Car& c) {
    Actor a;
    a.kind = ActorKind::kCar;
    a.car = c;
    AddActor(std::move(a));
  }

  void AddCart(const Cart& c) {
    Actor a;
    a.kind = ActorKind::kCart;
    a.cart = c;
    AddActor(std::move(a));
  }

  // The box added last (to adjust what Add drew at random, such as its texture shift).
  Box& LastBox() { return world_.static_boxes.back(); }
  Rng& rng() { return rng_; }
  const TextureSet& textures() const { return tex_; }

 private:
  // Every actor gets the next instance id, in the order added (the random streams rely on it).
  void AddActor(Actor a) {
    a.instance = NewInstance();
    world_.actors.push_back(std::move(a));
  }

  World& world_;
  Rng& rng_;
  PeopleStyle style_ = PeopleStyle::kBoxes;
  Rng body_rng_{0};
  const TextureSet& tex_;
};

// Sum of sinusoids with seeded phases: smooth like a hand-held camera, not periodic at first sight.
struct Wobble {
  double amp[3], period[3], phase[3];
  Wobble(Rng& rng, double amplitude, double min_period, double max_period) {
    for (int i = 0; i < 3; ++i) {
      amp[i] = amplitude * (i == 0 ? 1.0 : 0.3 / i);
      period[i] = rng.Uniform(min_period, max_period) / (i + 1);
      phase[i] = rng.Uniform(0, 2 * M_PI);
    }
  }
  double operator()(double t) const {
    double v = 0.0;
    for (int i = 0; i < 3; ++i) v += amp[i] * std::sin(2 * M_PI * t / period[i] + phase[i]);
    return v;
  }
};

// presets_aliasing.cc: the street of identical houses and the corridor of identical doors, each
// straight and as a ring (street_repeat, street_repeat_loop, corridor, corridor_loop).
bool IsAliasingPreset(const std::string& name);
void MakeAliasingPreset(const std::string& name, Builder& b, SequenceSpec* spec, int width,
                        int height);

inline SE3 Rotate(const SE3& T, double rx, double ry, double rz) {
  const Eigen::Quaterniond q = Eigen::AngleAxisd(rz, Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(ry, Vector3d::UnitY()) *
                               Eigen::AngleAxisd(rx, Vector3d::UnitX());
  return SE3(T.rotation() * q, T.translation());
}

}  // namespace moslam::synth::internal
