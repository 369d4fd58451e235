#include "moslam/synth/body.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include <Eigen/Geometry>

#include "moslam/util/check.h"

namespace moslam::synth {
namespace {

using Eigen::Vector3d;
using Eigen::Vector3f;
using Influence = BodyModel::Influence;

Influence Only(int bone) { return {bone, bone, 0.0f}; }
Influence Blend(int a, int b, float w_b) { return {a, b, w_b}; }

// One cross-section of a vertical tube: height z of its centre (x, y offsets in the person's
// frame), elliptic radii along x (front-back) and y (left-right), and its bones.
struct Ring {
  double x, y, z, rx, ry;
  Influence influence;
};

// A generalized cylinder through `rings` (ordered along the tube), closed by rounded caps where
// asked. Texture coordinates are metric (one repeat per `tile` metres) with the seam at the back.
void Tube(BodyModel* m, const std::vector<Ring>& rings, int texture, const Vector3f& colour,
          double tile, bool cap_first, bool cap_last) {
  MOSLAM_CHECK(rings.size() >= 2);
  constexpr int kSides = 16;
  constexpr int kCapRings = 3;
  Mesh& mesh = m->rest();
  const uint32_t first_index = static_cast<uint32_t>(mesh.indices.size());
  // Rings with caps: each cap adds rings that shrink towards the axis, as a quarter ellipse.
  struct Row {
    Vector3d c;
    double rx, ry;
    Vector3d axis_shift;  // normal tilt towards the axis (caps)
    Influence influence;
    double v;  // texture coordinate along the tube, metres
  };
  std::vector<Row> rows;
  auto axis_at = [&](size_t i, size_t j) {
    const Ring& a = rings[i];
    const Ring& b = rings[j];
    return Vector3d(b.x - a.x, b.y - a.y, b.z - a.z).normalized();
  };
  double v = 0.0;
  auto add_cap = [&](const Ring& r, const Vector3d& outward, bool leading) {
    const double depth = 0.8 * std::min(r.rx, r.ry);
    for (int k = kCapRings; k >= 1; --k) {
      const int kk = leading ? k : kCapRings + 1 - k;
      const double a = 0.5 * M_PI * kk / kCapRings;  // kk = kCapRings: the pole
      const double scale = std::cos(a);
      rows.push_back({Vector3d(r.x, r.y, r.z) + outward * depth * std::sin(a), r.rx * scale,
                      r.ry * scale, outward * std::sin(a), r.influence,
                      v + (leading ? -1 : 1) * depth * std::sin(a)});
    }
  };
  if (cap_first) add_cap(rings.front(), -axis_at(0, 1), true);
  for (size_t i = 0; i < rings.size(); ++i) {
    if (i > 0) {
      const Ring& a = rings[i - 1];
      v += Vector3d(rings[i].x - a.x, rings[i].y - a.y, rings[i].z - a.z).norm();
    }
    const Ring& r = rings[i];
    rows.push_back({Vector3d(r.x, r.y, r.z), r.rx, r.ry, Vector3d::Zero(), r.influence, v});
  }
  if (cap_last) add_cap(rings.back(), axis_at(rings.size() - 2, rings.size() - 1), false);

  const double perimeter =
      2 * M_PI * std::sqrt(0.5 * (rings[0].rx * rings[0].rx + rings[0].ry * rings[0].ry));
  const uint32_t base = static_cast<uint32_t>(mesh.vertices.size());
  for (const Row& row : rows) {
    for (int k = 0; k <= kSides; ++k) {
      const double theta = 2 * M_PI * k / kSides;
      // theta = 0 at the back (-x): the texture seam is where a viewer looks least.
      const double cx = -std::cos(theta), sy = -std::sin(theta);
      MeshVertex vertex;
      vertex.p = (row.c + Vector3d(row.rx * cx, row.ry * sy, 0)).cast<float>();
      Vector3d n(cx / std::max(row.rx, 1e-6), sy / std::max(row.ry, 1e-6), 0);
      n = n.normalized() * std::sqrt(std::max(0.0, 1.0 - row.axis_shift.squaredNorm())) +
          row.axis_shift;
      vertex.n = n.normalized().cast<float>();
      vertex.uv = Eigen::Vector2f(static_cast<float>(theta / (2 * M_PI) * perimeter / tile),
                                  static_cast<float>(row.v / tile));
      vertex.colour = colour;
      m->AddVertex(vertex, row.influence);
    }
  }
  const uint32_t stride = kSides + 1;
  for (uint32_t r = 0; r + 1 < rows.size(); ++r) {
    for (uint32_t k = 0; k < static_cast<uint32_t>(kSides); ++k) {
      const uint32_t a = base + r * stride + k, b = a + 1, c = a + stride, d = c + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
    }
  }
  mesh.parts.push_back(
      {texture, first_index, static_cast<uint32_t>(mesh.indices.size()) - first_index});
}

// An ellipsoid with centre c and radii (person axes), bound to one bone. `min_latitude(lon)`
// (radians; lon 0 = forward) cuts the part below a latitude away: hair is a cut ellipsoid.
void Ellipsoid(BodyModel* m, const Vector3d& c, const Vector3d& radii, int bone, int texture,
               const Vector3f& colour, double tile,
               const std::function<double(double)>& min_latitude = nullptr) {
  constexpr int kLon = 16, kLat = 10;
  Mesh& mesh = m->rest();
  const uint32_t first_index = static_cast<uint32_t>(mesh.indices.size());
  const uint32_t base = static_cast<uint32_t>(mesh.vertices.size());
  const double perimeter =
      2 * M_PI * std::sqrt(0.5 * (radii.x() * radii.x() + radii.y() * radii.y()));
  for (int i = 0; i <= kLat; ++i) {
    for (int k = 0; k <= kLon; ++k) {
      const double lon = M_PI + 2 * M_PI * k / kLon;  // seam at the back
      const double lo = min_latitude ? min_latitude(std::remainder(lon, 2 * M_PI)) : -M_PI / 2;
      const double lat = lo + (M_PI / 2 - lo) * i / kLat;
      const Vector3d unit(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon),
                          std::sin(lat));
      MeshVertex vertex;
      vertex.p = (c + unit.cwiseProduct(radii)).cast<float>();
      vertex.n = unit.cwiseQuotient(radii).normalized().cast<float>();
      vertex.uv = Eigen::Vector2f(static_cast<float>(k / double(kLon) * perimeter / tile),
                                  static_cast<float>(lat * radii.z() / tile));
      vertex.colour = colour;
      m->AddVertex(vertex, Only(bone));
    }
  }
  const uint32_t stride = kLon + 1;
  for (uint32_t i = 0; i < static_cast<uint32_t>(kLat); ++i) {
    for (uint32_t k = 0; k < static_cast<uint32_t>(kLon); ++k) {
      const uint32_t a = base + i * stride + k, b = a + 1, cc = a + stride, d = cc + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, cc});
    }
  }
  mesh.parts.push_back(
      {texture, first_index, static_cast<uint32_t>(mesh.indices.size()) - first_index});
}

// A point on the surface of the ellipsoid (c, radii) at latitude/longitude (lon 0 = forward).
Vector3d OnEllipsoid(const Vector3d& c, const Vector3d& radii, double lat, double lon) {
  return c + Vector3d(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat))
                 .cwiseProduct(radii);
}

void AddHead(BodyModel* m, double H) {
  const BodyShape& s = m->shape();
  const Vector3f white(1, 1, 1);
  const Vector3d head_c(0.012 * H, 0, 0.935 * H);
  const Vector3d head_r(0.058 * H, 0.047 * H, 0.068 * H);
  Ellipsoid(m, head_c, head_r, kHead, -1, s.skin, 0.2);
  Ellipsoid(m, Vector3d(0.022 * H, 0, 0.9 * H), Vector3d(0.045, 0.037, 0.036) * H, kHead, -1,
            s.skin, 0.2);  // jaw and chin
  // Hair: the head's ellipsoid a little larger, from the hairline (high at the forehead, low at
  // the nape) up.
  const Vector3d hair_r = head_r + Vector3d::Constant(0.006 * H);
  Ellipsoid(m, head_c + Vector3d(-0.003 * H, 0, 0.002 * H), hair_r, kHead, -2, s.hair, 0.1,
            [](double lon) { return 0.48 - 0.54 * (1 - std::cos(lon)); });
  if (s.long_hair) {
    Tube(m,
         {{-0.035 * H, 0, 0.93 * H, 0.035 * H, 0.05 * H, Only(kHead)},
          {-0.045 * H, 0, 0.86 * H, 0.03 * H, 0.058 * H, Only(kHead)},
          {-0.05 * H, 0, 0.8 * H, 0.02 * H, 0.055 * H, Blend(kHead, kChest, 0.6f)}},
         -2, s.hair, 0.1, true, true);
  }
  const Vector3f iris(0.18f, 0.11f, 0.06f);
  const Vector3f lips(std::min(1.f, 0.62f * s.skin.x() + 0.12f), 0.42f * s.skin.y(),
                      0.45f * s.skin.z());
  for (int side = -1; side <= 1; side += 2) {
    const double lon = 0.36 * side;
    const Vector3d eye = OnEllipsoid(head_c, head_r, 0.0, lon) - Vector3d(0.004 * H, 0, 0);
    Ellipsoid(m, eye, Vector3d(0.006, 0.009, 0.0055) * H, kHead, -1, white * 0.92f, 0.2);
    Ellipsoid(m, eye + Vector3d(0.0045 * H, 0, 0), Vector3d(0.0025, 0.0042, 0.0042) * H, kHead, -1,
              iris, 0.2);
    Ellipsoid(m, OnEllipsoid(head_c, head_r, 0.13, lon), Vector3d(0.004, 0.013, 0.0025) * H, kHead,
              -1, s.hair, 0.2);  // brow
    Ellipsoid(m, OnEllipsoid(head_c, head_r, 0.0, M_PI / 2 * side) + Vector3d(-0.005 * H, 0, 0),
              Vector3d(0.014, 0.007, 0.021) * H, kHead, -1, s.skin * 0.93f, 0.2);  // ear
  }
  Ellipsoid(m, OnEllipsoid(head_c, head_r, -0.1, 0) + Vector3d(0.004 * H, 0, 0),
            Vector3d(0.012, 0.009, 0.021) * H, kHead, -1, s.skin * 0.97f, 0.2);  // nose
  Ellipsoid(m, OnEllipsoid(head_c, head_r, -0.32, 0) + Vector3d(0.004 * H, 0, -0.004 * H),
            Vector3d(0.004, 0.016, 0.0035) * H, kHead, -1, lips, 0.2);  // mouth
  Tube(m,
       {{0.005 * H, 0, 0.8 * H, 0.032 * H, 0.034 * H, Blend(kHead, kChest, 0.6f)},
        {0.008 * H, 0, 0.85 * H, 0.03 * H, 0.032 * H, Only(kHead)},
        {0.01 * H, 0, 0.895 * H, 0.03 * H, 0.032 * H, Only(kHead)}},
       -1, s.skin, 0.2, false, false);  // neck
}

void AddTorso(BodyModel* m, double H, double g) {
  const BodyShape& s = m->shape();
  const double hips = s.female ? 1.08 : 1.0, waist = s.female ? 0.88 : 1.0;
  const double shoulders = s.female ? 0.9 : 1.0;
  const Vector3f& cloth = s.trousers_colour;
  if (!s.skirt) {
    Tube(m,
         {{0, 0, 0.465 * H, 0.07 * H * g, 0.08 * H * g, Only(kPelvis)},
          {0, 0, 0.5 * H, 0.088 * H * g, 0.105 * H * g * hips, Only(kPelvis)},
          {0, 0, 0.54 * H, 0.092 * H * g, 0.11 * H * g * hips, Only(kPelvis)},
          {0, 0, 0.59 * H, 0.085 * H * g, 0.1 * H * g * waist, Blend(kPelvis, kChest, 0.3f)}},
         s.trousers, cloth, 0.3, true, false);
  } else {
    // A skirt: from the waist to above the knee, open at the hem, moved by the pelvis only.
    Tube(m,
         {{0, 0, 0.6 * H, 0.085 * H * g, 0.1 * H * g * waist, Blend(kPelvis, kChest, 0.3f)},
          {0, 0, 0.5 * H, 0.1 * H * g, 0.122 * H * g, Only(kPelvis)},
          {0, 0, 0.41 * H, 0.115 * H * g, 0.14 * H * g, Only(kPelvis)},
          {0, 0, 0.34 * H, 0.125 * H * g, 0.15 * H * g, Only(kPelvis)}},
         s.trousers, cloth, 0.3, false, false);
  }
  const double bust = s.female ? 1.06 : 1.0;
  Tube(
      m,
      {{0, 0, 0.575 * H, 0.089 * H * g, 0.104 * H * g * hips, Blend(kPelvis, kChest, 0.3f)},
       {0, 0, 0.62 * H, 0.082 * H * g * waist, 0.093 * H * g * waist, Blend(kPelvis, kChest, 0.6f)},
       {0, 0, 0.68 * H, 0.09 * H * g, 0.1 * H * g, Only(kChest)},
       {0.004 * H, 0, 0.73 * H, 0.1 * H * g * bust, 0.106 * H * g * shoulders, Only(kChest)},
       {0, 0, 0.78 * H, 0.094 * H * g, 0.112 * H * g * shoulders, Only(kChest)},
       {-0.004 * H, 0, 0.81 * H, 0.075 * H * g, 0.104 * H * g * shoulders, Only(kChest)},
       {0, 0, 0.83 * H, 0.045 * H, 0.052 * H, Only(kChest)}},
      s.shirt, s.shirt_colour, 0.4, false, true);
}

void AddLeg(BodyModel* m, double H, double g, int side) {
  const BodyShape& s = m->shape();
  const int thigh = side > 0 ? kThighL : kThighR, shin = thigh + 1, foot = thigh + 2;
  const double y = side * 0.05 * H;
  const int tex = s.skirt ? -1 : s.trousers;
  const Vector3f colour = s.skirt ? s.skin : s.trousers_colour;
  Tube(m,
       {{0, y, 0.55 * H, 0.058 * H * g, 0.055 * H * g, Only(thigh)},
        {0, y, 0.5 * H, 0.056 * H * g, 0.052 * H * g, Only(thigh)},
        {0, y, 0.42 * H, 0.048 * H * g, 0.045 * H * g, Only(thigh)},
        {0, y, 0.33 * H, 0.038 * H * g, 0.036 * H * g, Blend(thigh, shin, 0.15f)},
        {0, y, 0.295 * H, 0.034 * H * g, 0.033 * H * g, Blend(thigh, shin, 0.5f)}},
       tex, colour, 0.3, true, true);
  Tube(m,
       {{0, y, 0.3 * H, 0.034 * H * g, 0.033 * H * g, Blend(shin, thigh, 0.5f)},
        {0, y, 0.27 * H, 0.035 * H * g, 0.033 * H * g, Blend(shin, thigh, 0.15f)},
        {-0.005 * H, y, 0.22 * H, 0.037 * H * g, 0.032 * H * g, Only(shin)},
        {-0.002 * H, y, 0.13 * H, 0.026 * H * g, 0.024 * H * g, Only(shin)},
        {0, y, 0.07 * H, 0.021 * H, 0.02 * H, Blend(shin, foot, 0.2f)},
        {0, y, 0.05 * H, 0.02 * H, 0.019 * H, Blend(shin, foot, 0.5f)}},
       tex, colour, 0.3, false, true);
  Ellipsoid(m, Vector3d(0.036 * H, y, 0.023 * H), Vector3d(0.077 * H, 0.03 * H, 0.025 * H), foot,
            s.shoes, s.shoes_colour, 0.2);
}

void AddArm(BodyModel* m, double H, double g, int side) {
  const BodyShape& s = m->shape();
  const int upper = side > 0 ? kUpperArmL : kUpperArmR, fore = upper + 1, hand = upper + 2;
  const double y = m->skeleton().joint[static_cast<size_t>(upper)].y();
  const Vector3f& cloth = s.shirt_colour;
  const double sleeve_end = s.short_sleeves ? 0.72 * H : 0.0;
  if (s.short_sleeves) {
    Tube(m,
         {{0, y, 0.8 * H, 0.033 * H * g, 0.033 * H * g, Only(upper)},
          {0, y, 0.78 * H, 0.034 * H * g, 0.034 * H * g, Only(upper)},
          {0, y, sleeve_end, 0.031 * H * g, 0.031 * H * g, Only(upper)}},
         s.shirt, cloth, 0.4, true, false);
  }
  const int arm_tex = s.short_sleeves ? -1 : s.shirt;
  const Vector3f arm_colour = s.short_sleeves ? s.skin : cloth;
  Tube(m,
       {{0, y, 0.8 * H, 0.03 * H * g, 0.03 * H * g, Only(upper)},
        {0, y, 0.78 * H, 0.031 * H * g, 0.031 * H * g, Only(upper)},
        {0, y, 0.7 * H, 0.027 * H * g, 0.027 * H * g, Only(upper)},
        {0, y, 0.64 * H, 0.024 * H * g, 0.024 * H * g, Blend(upper, fore, 0.3f)}},
       arm_tex, arm_colour, 0.4, true, true);
  const int fore_tex = s.short_sleeves ? -1 : s.shirt;
  Tube(m,
       {{0, y, 0.63 * H, 0.024 * H * g, 0.024 * H * g, Blend(fore, upper, 0.4f)},
        {0.002 * H, y, 0.58 * H, 0.025 * H * g, 0.024 * H * g, Only(fore)},
        {0, y, 0.52 * H, 0.02 * H * g, 0.019 * H * g, Only(fore)},
        {0, y, 0.485 * H, 0.016 * H, 0.015 * H, Blend(fore, hand, 0.3f)}},
       fore_tex, arm_colour, 0.4, true, true);
  // Hand with the palm towards the thigh, and a thumb in front.
  Ellipsoid(m, Vector3d(0.003 * H, y, 0.43 * H), Vector3d(0.024, 0.011, 0.048) * H, hand, -1,
            s.skin, 0.2);
  Ellipsoid(m, Vector3d(0.022 * H, y - side * 0.004 * H, 0.45 * H),
            Vector3d(0.008, 0.008, 0.02) * H, hand, -1, s.skin, 0.2);
}

}  // namespace

Skeleton Skeleton::For(const BodyShape& shape) {
  const double H = shape.height_m;
  Skeleton s;
  const double hip_y = 0.05 * H;
  const double shoulder_y = (0.118 + 0.015 * shape.build - (shape.female ? 0.01 : 0.0)) * H;
  s.joint[kPelvis] = Vector3d(0, 0, 0.53 * H);
  s.joint[kChest] = Vector3d(0, 0, 0.62 * H);
  s.joint[kHead] = Vector3d(0, 0, 0.845 * H);
  for (int side = -1; side <= 1; side += 2) {
    const size_t leg = side > 0 ? kThighL : kThighR, arm = side > 0 ? kUpperArmL : kUpperArmR;
    s.joint[leg] = Vector3d(0, side * hip_y, 0.53 * H);
    s.joint[leg + 1] = Vector3d(0, side * hip_y, 0.285 * H);
    s.joint[leg + 2] = Vector3d(0, side * hip_y, 0.039 * H);
    s.joint[arm] = Vector3d(0, side * shoulder_y, 0.805 * H);
    s.joint[arm + 1] = Vector3d(0, side * shoulder_y, 0.619 * H);
    s.joint[arm + 2] = Vector3d(0, side * shoulder_y, 0.473 * H);
  }
  s.thigh = 0.245 * H;
  s.shin = 0.246 * H;
  s.ankle_height = 0.039 * H;
  s.heel = 0.035 * H;
  s.ball = 0.105 * H;
  s.upper_arm = 0.186 * H;
  s.forearm = 0.146 * H;
  return s;
}

BodyModel::BodyModel(const BodyShape& shape) : shape_(shape), skeleton_(Skeleton::For(shape)) {
  MOSLAM_CHECK(shape.height_m > 0.5 && shape.height_m < 2.5) << "body height " << shape.height_m;
  const double H = shape.height_m, g = 0.85 + 0.4 * std::clamp(shape.build, 0.0, 1.0);
  AddTorso(this, H, g);
  AddHead(this, H);
  for (int side = -1; side <= 1; side += 2) {
    AddLeg(this, H, g, side);
    AddArm(this, H, g, side);
  }
}

void BodyModel::AddVertex(const MeshVertex& v, const Influence& influence) {
  rest_.vertices.push_back(v);
  bones_.push_back({influence.bone_a, influence.bone_b});
  weights_.push_back({1.0f - influence.w_b, influence.w_b});
}

BodyPose BodyModel::RestPose() const {
  BodyPose pose;
  for (size_t b = 0; b < kNumBones; ++b) {
    pose[b] = geometry::SE3(Eigen::Quaterniond::Identity(), skeleton_.joint[b]);
  }
  return pose;
}

Mesh BodyModel::Skin(const BodyPose& pose, uint8_t class_id, uint16_t instance) const {
  // Linear blend skinning: v = sum_j w_j T_world_j B_j^-1 v_rest, with B_j the rest frame of bone
  // j (a translation to its joint, since rest frames have the person's axes).
  std::array<Eigen::Matrix3f, kNumBones> R;
  std::array<Eigen::Vector3f, kNumBones> t;
  for (size_t b = 0; b < kNumBones; ++b) {
    R[b] = pose[b].rotation().toRotationMatrix().cast<float>();
    t[b] = (pose[b].translation() - pose[b].rotation() * skeleton_.joint[b]).cast<float>();
  }
  Mesh out;
  out.indices = rest_.indices;
  out.parts = rest_.parts;
  out.class_id = class_id;
  out.instance = instance;
  out.vertices.resize(rest_.vertices.size());
  for (size_t i = 0; i < rest_.vertices.size(); ++i) {
    const MeshVertex& v = rest_.vertices[i];
    const auto [a, b] = bones_[i];
    const auto [wa, wb] = weights_[i];
    MeshVertex& o = out.vertices[i];
    o = v;
    const auto ua = static_cast<size_t>(a), ub = static_cast<size_t>(b);
    if (wb == 0.0f) {
      o.p = R[ua] * v.p + t[ua];
      o.n = R[ua] * v.n;
    } else {
      o.p = wa * (R[ua] * v.p + t[ua]) + wb * (R[ub] * v.p + t[ub]);
      o.n = (wa * (R[ua] * v.n) + wb * (R[ub] * v.n)).normalized();
    }
  }
  return out;
}

}  // namespace moslam::synth
