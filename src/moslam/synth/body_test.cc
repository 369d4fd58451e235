#include "moslam/synth/body.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "moslam/synth/gait.h"
#include "moslam/synth/presets.h"
#include "moslam/synth/renderer.h"
#include "moslam/synth/scene.h"
#include "moslam/synth/texture.h"

namespace moslam::synth {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
using geometry::SE3;

constexpr double kDeg = M_PI / 180.0;

// A straight path along +x.
void Straight(double s, Vector2d* xy, double* heading) {
  *xy = Vector2d(s, 0.0);
  *heading = 0.0;
}

// The ball of a foot (the stance pivot) in world coordinates.
Vector3d Ball(const Skeleton& sk, const SE3& T_world_foot) {
  return T_world_foot * Vector3d(sk.ball, 0, -sk.ankle_height);
}

TEST(Body, RestMeshHasUnitWeightsAndNormals) {
  const BodyModel body{BodyShape{}};
  ASSERT_GT(body.num_vertices(), 1000u);
  for (size_t i = 0; i < body.num_vertices(); ++i) {
    const auto w = body.weights(i);
    EXPECT_NEAR(w[0] + w[1], 1.0f, 1e-6f);
    EXPECT_NEAR(body.rest_vertex(i).n.norm(), 1.0f, 1e-4f);
  }
  // The rest mesh spans the body: feet at the floor, the top of the hair at the height.
  float lo = 1e9f, hi = -1e9f;
  for (size_t i = 0; i < body.num_vertices(); ++i) {
    lo = std::min(lo, body.rest_vertex(i).p.z());
    hi = std::max(hi, body.rest_vertex(i).p.z());
  }
  EXPECT_NEAR(lo, 0.0, 0.01);
  EXPECT_NEAR(hi, 1.75, 0.04);
}

TEST(Body, RestPoseSkinsToTheRestMesh) {
  const BodyModel body{BodyShape{}};
  const Mesh m = body.Skin(body.RestPose(), kPerson, 3);
  ASSERT_EQ(m.vertices.size(), body.num_vertices());
  EXPECT_EQ(m.instance, 3);
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    EXPECT_LT((m.vertices[i].p - body.rest_vertex(i).p).norm(), 1e-5f);
  }
}

TEST(Body, BentKneeMovesTheShinAndNotTheThighsHipEnd) {
  const BodyModel body{BodyShape{}};
  const Skeleton& sk = body.skeleton();
  BodyPose pose = body.RestPose();
  // Bend the left knee by 60 degrees: the shin and the foot turn about the knee.
  const SE3 bend(Eigen::Quaterniond(Eigen::AngleAxisd(60 * kDeg, Vector3d::UnitY())),
                 Vector3d::Zero());
  const SE3 T_knee = pose[kShinL];
  pose[kShinL] = T_knee * bend;
  pose[kFootL] =
      pose[kShinL] * SE3(Eigen::Quaterniond::Identity(), sk.joint[kFootL] - sk.joint[kShinL]);
  const Mesh bent = body.Skin(pose, kPerson, 1);
  int shin_moved = 0, shin = 0, thigh_top = 0;
  for (size_t i = 0; i < body.num_vertices(); ++i) {
    const auto bones = body.bones(i);
    const auto w = body.weights(i);
    const float shift = (bent.vertices[i].p - body.rest_vertex(i).p).norm();
    const bool only_shin = bones[0] == kShinL && w[1] == 0.0f;
    const bool only_thigh = bones[0] == kThighL && w[1] == 0.0f;
    if (only_shin) {
      ++shin;
      // A point r below the knee moves by 2 r sin(30 deg) = r.
      const double r = (body.rest_vertex(i).p.cast<double>() - sk.joint[kShinL]).norm();
      if (shift > 0.5 * r) ++shin_moved;
    }
    if (only_thigh && body.rest_vertex(i).p.z() > 0.5 * 1.75) {
      ++thigh_top;
      EXPECT_LT(shift, 1e-6f) << "thigh vertex " << i << " near the hip moved";
    }
  }
  EXPECT_GE(shin, 30);
  EXPECT_EQ(shin_moved, shin);
  EXPECT_GT(thigh_top, 20);
}

TEST(Gait, StanceFootDoesNotSlide) {
  const Skeleton sk = Skeleton::For(BodyShape{});
  const double stride = StrideLength(1.75, 1.2);
  EXPECT_NEAR(StrideLength(1.75, 1.3), 1.45, 1e-9);
  // Follow the left foot over three gait cycles at 1/200 of a cycle.
  int stances = 0;
  bool in_stance = false;
  Vector3d first = Vector3d::Zero();
  double worst = 0.0;
  for (int i = 0; i < 600; ++i) {
    const double s = 0.3 + i * stride / 200;
    const FootPlacement f = PlaceFoot(sk, Straight, s, stride, 1);
    const Vector3d ball = Ball(sk, f.T_world_foot);
    if (f.stance && !in_stance) {
      ++stances;
      first = ball;
    }
    if (f.stance) {
      worst = std::max(worst, (ball - first).norm());
      EXPECT_LT(std::abs(ball.z()), 0.02) << "stance ball above the floor at s " << s;
    }
    in_stance = f.stance;
  }
  EXPECT_GE(stances, 3);
  EXPECT_LT(worst, 0.02);
}

TEST(Gait, WalkingLegsReachTheirFeetAndKneesFlexInSwing) {
  const Skeleton sk = Skeleton::For(BodyShape{});
  const double stride = StrideLength(1.75, 1.2);
  double max_knee = 0.0, min_knee = 1e9, min_pelvis = 1e9, max_pelvis = 0.0;
  for (int i = 0; i < 400; ++i) {
    const double s = i * stride / 200;
    const BodyPose pose = WalkingPose(sk, Straight, s, stride, 0.0);
    // The shin's origin (knee) plus its length reaches the foot's origin (ankle).
    const Vector3d knee_to_ankle = pose[kFootL].translation() - pose[kShinL].translation();
    EXPECT_NEAR(knee_to_ankle.norm(), sk.shin, 1e-6);
    EXPECT_NEAR((pose[kShinL].translation() - pose[kThighL].translation()).norm(), sk.thigh, 1e-6);
    const Vector3d thigh_dir = pose[kThighL].rotation() * -Vector3d::UnitZ();
    const Vector3d shin_dir = pose[kShinL].rotation() * -Vector3d::UnitZ();
    const double knee = std::acos(std::clamp(thigh_dir.dot(shin_dir), -1.0, 1.0));
    max_knee = std::max(max_knee, knee);
    min_knee = std::min(min_knee, knee);
    min_pelvis = std::min(min_pelvis, pose[kPelvis].translation().z());
    max_pelvis = std::max(max_pelvis, pose[kPelvis].translation().z());
    // The body moves along the path: the pelvis stays within a stride of s.
    EXPECT_NEAR(pose[kPelvis].translation().x(), s, 0.05);
  }
  // Normal gait: knee flexion peaks near 60 degrees in swing and stays small in stance.
  EXPECT_GT(max_knee, 45 * kDeg);
  EXPECT_LT(max_knee, 75 * kDeg);
  EXPECT_LT(min_knee, 12 * kDeg);
  // The pelvis bobs by a few centimetres.
  EXPECT_GT(max_pelvis - min_pelvis, 0.01);
  EXPECT_LT(max_pelvis - min_pelvis, 0.08);
}

TEST(Gait, SeatedFeetRestOnTheFloor) {
  const Skeleton sk = Skeleton::For(BodyShape{});
  for (double w = 0; w < 20; w += 0.7) {
    const BodyPose pose = SeatedPose(sk, Vector2d(1, 2), 0.3, 0.48, w);
    EXPECT_NEAR(pose[kFootL].translation().z(), sk.ankle_height, 0.01);
    EXPECT_NEAR(pose[kFootR].translation().z(), sk.ankle_height, 0.01);
    EXPECT_NEAR(pose[kPelvis].translation().z(), 0.48, 1e-9);
  }
}

// One walking body in front of the camera, alone in a room.
SequenceSpec OneBody(const TextureSet& textures) {
  SequenceSpec spec = MakePreset("w_static", 5, textures, 160, 120, PeopleStyle::kBodies);
  return spec;
}

TEST(BodyRender, MaskCoversTheProjectedMeshAndRendersRepeatably) {
  const TextureSet textures = TextureSet::Procedural(5, 2, 64);
  const SequenceSpec spec = OneBody(textures);
  ASSERT_FALSE(spec.world.actors.empty());
  Renderer renderer(spec.camera.width, spec.camera.height, textures);
  const camera::PinholeOptions& c = spec.camera;
  int checked = 0, frames_with_people = 0;
  for (int k = 0; k < 6; ++k) {
    const double t = 1.3 * k;
    const SE3 T_cam_world = spec.T_world_cam(t).Inverse();
    const std::vector<Mesh> meshes = spec.world.MeshesAt(t);
    ASSERT_EQ(meshes.size(), spec.world.actors.size());
    EXPECT_TRUE(spec.world.BoxesAt(t).size() > 0);
    RenderOutput a, b;
    renderer.Render(spec.world.BoxesAt(t), meshes, c, T_cam_world, spec.lighting, &a);
    renderer.Render(spec.world.BoxesAt(t), meshes, c, T_cam_world, spec.lighting, &b);
    EXPECT_EQ(cv::norm(a.rgb, b.rgb, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.instance, b.instance, cv::NORM_INF), 0.0);
    if (cv::countNonZero(a.class_id == kPerson) > 50) ++frames_with_people;
    // Every vertex of a body that projects into the image lands on that body's pixels or on a
    // nearer surface (an occluder): masks line up with what is drawn.
    for (const Mesh& m : meshes) {
      for (size_t i = 0; i < m.vertices.size(); i += 7) {
        const Vector3d p = T_cam_world * m.vertices[i].p.cast<double>();
        if (p.z() < 0.3) continue;
        const int u = static_cast<int>(std::lround(c.fx * p.x() / p.z() + c.cx));
        const int v = static_cast<int>(std::lround(c.fy * p.y() / p.z() + c.cy));
        if (u < 1 || v < 1 || u >= c.width - 1 || v >= c.height - 1) continue;
        bool ok = false;
        for (int dv = -1; dv <= 1 && !ok; ++dv) {
          for (int du = -1; du <= 1 && !ok; ++du) {
            const float z = a.depth.at<float>(v + dv, u + du);
            ok = a.instance.at<uint16_t>(v + dv, u + du) == m.instance || (z > 0 && z < p.z());
          }
        }
        EXPECT_TRUE(ok) << "vertex " << i << " of instance " << m.instance << " at " << u << ","
                        << v;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100);
  EXPECT_GE(frames_with_people, 2);
}

TEST(BodyRender, SameSceneAndCameraWithEitherStyle) {
  const TextureSet textures = TextureSet::Procedural(5, 2, 64);
  const SequenceSpec boxes = MakePreset("w_xyz", 9, textures, 160, 120, PeopleStyle::kBoxes);
  const SequenceSpec bodies = MakePreset("w_xyz", 9, textures, 160, 120, PeopleStyle::kBodies);
  ASSERT_EQ(boxes.world.static_boxes.size(), bodies.world.static_boxes.size());
  ASSERT_EQ(boxes.world.actors.size(), bodies.world.actors.size());
  for (double t : {0.0, 3.0, 9.0}) {
    EXPECT_LT((boxes.T_world_cam(t).translation() - bodies.T_world_cam(t).translation()).norm(),
              1e-12);
  }
  EXPECT_TRUE(boxes.world.MeshesAt(1.0).empty());
  EXPECT_EQ(bodies.world.MeshesAt(1.0).size(), bodies.world.actors.size());
  // Moving people are found moving as bodies too.
  EXPECT_EQ(bodies.world.MovingInstances(2.0, 1.0 / 30).size(),
            boxes.world.MovingInstances(2.0, 1.0 / 30).size());
}

}  // namespace
}  // namespace moslam::synth
