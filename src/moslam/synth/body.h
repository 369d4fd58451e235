// Human bodies as smooth skinned meshes (issue 25): a parametric body of rounded segments on a
// skeleton of 15 bones, deformed by linear blend skinning (Magnenat-Thalmann et al., "Joint-
// dependent local deformations for hand animation and object grasping", Graphics Interface 1988),
// with proportions from anthropometric segment lengths as fractions of the body height (Drillis &
// Contini 1966 as tabulated by D. A. Winter, "Biomechanics and Motor Control of Human Movement",
// 4th ed. 2009, fig. 4.1), skin tones, hair, a face (eyes, brows, nose, mouth, ears) and clothes.
//
// Why meshes: networks trained on real photographs do not see the box figures of scene.h as
// people (DeepLabV3-VOC person IoU 0.05 on w_xyz, docs/EVALUATION.md); round limbs, a head with a
// face, hair, hands and shading are what such networks key on.
//
// Bones have frames whose axes, at the rest pose, are the person's (x forward, y left, z up) and
// whose origin is the joint; limbs hang along their bone's -z. Poses (gait.h) give each bone's
// world frame; Skin() maps the rest mesh through them.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "moslam/geometry/se3.h"

namespace moslam::synth {

enum Bone : int {
  kPelvis = 0,
  kChest,
  kHead,
  kThighL,
  kShinL,
  kFootL,
  kThighR,
  kShinR,
  kFootR,
  kUpperArmL,
  kForearmL,
  kHandL,
  kUpperArmR,
  kForearmR,
  kHandR,
  kNumBones
};

// One vertex of a triangle mesh as the renderer draws it: world (or rest) position and normal,
// texture coordinates in texture repeats, and a colour that multiplies the texture.
struct MeshVertex {
  Eigen::Vector3f p = Eigen::Vector3f::Zero();
  Eigen::Vector3f n = Eigen::Vector3f::UnitZ();
  Eigen::Vector2f uv = Eigen::Vector2f::Zero();
  Eigen::Vector3f colour = Eigen::Vector3f::Ones();
};

// Triangles [first, first + count) of the index list drawn with one texture (-1: plain colour,
// -2: plain cloth, synth::MakeFabricTexture, in the vertices' colour).
struct MeshPart {
  int texture = -1;
  uint32_t first = 0, count = 0;
};

struct Mesh {
  std::vector<MeshVertex> vertices;
  std::vector<uint32_t> indices;  // three per triangle
  std::vector<MeshPart> parts;
  uint8_t class_id = 0;
  uint16_t instance = 0;
};

// What a body looks like; drawn at random by the scene builder (scene_builder.h).
struct BodyShape {
  double height_m = 1.75;
  double build = 0.5;   // girth: 0 slim .. 1 heavy
  bool female = false;  // narrower waist and shoulders, wider hips
  bool skirt = false;   // a skirt to above the knee instead of trousers
  bool short_sleeves = false;
  bool long_hair = false;
  Eigen::Vector3f skin = Eigen::Vector3f(0.85f, 0.64f, 0.5f);  // linear RGB in [0, 1]
  Eigen::Vector3f hair = Eigen::Vector3f(0.2f, 0.14f, 0.1f);
  int shirt = 0, trousers = 0, shoes = 0;  // textures (TextureSet indices; -1 plain, -2 cloth)
  Eigen::Vector3f shirt_colour = Eigen::Vector3f::Ones();  // multiplies the texture
  Eigen::Vector3f trousers_colour = Eigen::Vector3f::Ones();
  Eigen::Vector3f shoes_colour = Eigen::Vector3f::Constant(0.45f);
};

// Joint positions of the rest pose (standing, arms hanging) in the person's frame (feet on z = 0)
// and the segment lengths the poses need, all from the body height.
struct Skeleton {
  std::array<Eigen::Vector3d, kNumBones> joint;  // rest position of each bone's origin
  double thigh = 0, shin = 0, ankle_height = 0;  // metres
  double heel = 0, ball = 0;  // heel behind and ball of the foot before the ankle
  double upper_arm = 0, forearm = 0;
  static Skeleton For(const BodyShape& shape);
};

// The posed skeleton: each bone's world frame (rest frame axes = person axes).
using BodyPose = std::array<geometry::SE3, kNumBones>;

// A body's rest mesh with skinning weights (up to two bones a vertex), built once per person.
class BodyModel {
 public:
  explicit BodyModel(const BodyShape& shape);

  const BodyShape& shape() const { return shape_; }
  const Skeleton& skeleton() const { return skeleton_; }
  // The rest pose: every bone at its rest joint, person frame = world frame.
  BodyPose RestPose() const;
  // The mesh deformed by `pose`, labelled class_id / instance.
  Mesh Skin(const BodyPose& pose, uint8_t class_id, uint16_t instance) const;
  size_t num_vertices() const { return rest_.vertices.size(); }
  // Rest position and bones/weights of vertex i (for tests).
  const MeshVertex& rest_vertex(size_t i) const { return rest_.vertices[i]; }
  std::array<int, 2> bones(size_t i) const { return bones_[i]; }
  std::array<float, 2> weights(size_t i) const { return weights_[i]; }

  // Builders used by the constructor (body.cc); public for the tube and ellipsoid helpers there.
  struct Influence {
    int bone_a = kPelvis, bone_b = kPelvis;
    float w_b = 0.0f;  // weight of bone_b; bone_a gets 1 - w_b
  };
  void AddVertex(const MeshVertex& v, const Influence& influence);
  Mesh& rest() { return rest_; }

 private:
  BodyShape shape_;
  Skeleton skeleton_;
  Mesh rest_;
  std::vector<std::array<int, 2>> bones_;
  std::vector<std::array<float, 2>> weights_;
};

}  // namespace moslam::synth
