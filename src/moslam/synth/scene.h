// What a synthetic scene is made of: textured boxes and skinned meshes. Rooms, furniture and cars
// are built from oriented boxes; a person is either a set of limb boxes whose poses change with
// time or a skinned body (body.h, gait.h).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "moslam/geometry/se3.h"
#include "moslam/synth/body.h"

namespace moslam::synth {

// Fixed class ids with PASCAL VOC names, so that VOC-trained segmentation models map directly.
enum ClassId : uint8_t {
  kBackground = 0,  // walls, floor, ceiling, shelves, road, facades: anything else
  kPerson = 1,
  kCar = 2,
  kChair = 3,
  kTvMonitor = 4,    // screens
  kDiningTable = 5,  // desks and tables
  kNumClasses = 6
};

const char* ClassName(int class_id);
// Person and car: the classes that can move (a parked car is movable but not moving).
bool IsMovableClass(int class_id);

struct Box {
  geometry::SE3 T_world_box;                       // centre and axes of the box
  Eigen::Vector3d half = Eigen::Vector3d::Ones();  // half extents along the box axes, metres
  int texture = 0;                                 // index into the TextureSet
  // Metres per texture repeat on every face; 0 stretches the texture once over each face
  // (posters, screens).
  double tile_m = 1.0;
  Eigen::Vector2d uv_offset = Eigen::Vector2d::Zero();  // texture shift, in repeats
  float tint = 1.0f;                                    // brightness multiplier
  uint8_t class_id = kBackground;
  uint16_t instance = 0;  // 0: no instance (background)
};

// Textures of one person's clothes and skin (indices into the TextureSet). With `body` set the
// person is a skinned mesh (body.h) of `shape` instead of boxes.
struct PersonLook {
  int shirt = 0, trousers = 0, skin = 0, hair = 0, shoes = 0;
  double height_m = 1.75;
  bool body = false;
  BodyShape shape;
};

// How people are drawn: boxes (the original figures) or skinned bodies (issue 25).
enum class PeopleStyle { kBoxes, kBodies };
// "boxes" / "bodies"; ParsePeopleStyle throws InputError on anything else.
const char* PeopleStyleName(PeopleStyle style);
PeopleStyle ParsePeopleStyle(const std::string& name);

// An articulated figure: head, hair, torso, upper and lower arms and legs, hands and feet, each a
// box hinged at its joint. Walking figures follow a closed path at constant speed with a gait
// cycle (legs and arms swing in opposition, knees bend, the body bobs); seated figures sit on a
// seat, sway, turn their heads and gesture.
class Person {
 public:
  // Walks around the closed polygon `path` (world x, y; z up) at `speed` m/s, starting `start_m`
  // metres along it.
  static Person Walking(const PersonLook& look, std::vector<Eigen::Vector2d> path, double speed,
                        double start_m);
  // Sits at `seat` (world x, y) facing `heading` (radians from +x), hips at seat_height metres.
  static Person Seated(const PersonLook& look, const Eigen::Vector2d& seat, double heading,
                       double seat_height, double phase);

  // The figure's boxes at time t (seconds), labelled kPerson / instance; none for a body.
  void AppendBoxes(double t, uint16_t instance, std::vector<Box>* boxes) const;
  // The body's mesh at time t; nothing for a box figure.
  void AppendMeshes(double t, uint16_t instance, std::vector<Mesh>* meshes) const;
  // The body's skeleton at time t (a body only).
  BodyPose PoseAt(double t) const;
  bool seated() const { return seated_; }
  const BodyModel* body() const { return body_.get(); }

 private:
  // Ground position and heading at time t.
  void Place(double t, Eigen::Vector2d* xy, double* heading) const;
  // ... at arc length s along the path (corners cut).
  void PathAt(double s, Eigen::Vector2d* xy, double* heading) const;
  PersonLook look_;
  std::shared_ptr<const BodyModel> body_;  // null: boxes
  bool seated_ = false;
  std::vector<Eigen::Vector2d> path_;
  std::vector<double> cumulative_;  // path length at each waypoint (closed: one more entry)
  double speed_ = 1.0, start_m_ = 0.0;
  Eigen::Vector2d seat_ = Eigen::Vector2d::Zero();
  double heading_ = 0.0, seat_height_ = 0.48, phase_ = 0.0;
};

// A car: body, cabin, roof and four wheels, driving along a straight lane at constant speed
// (speed 0: parked).
struct Car {
  Eigen::Vector2d start = Eigen::Vector2d::Zero();  // world x, y at t = 0
  double heading = 0.0;                             // radians from +x
  double speed = 0.0;                               // m/s along the heading
  int paint = 0, glass = 0, tyre = 0;
  Eigen::Vector3d size = Eigen::Vector3d(4.2, 1.8, 1.45);  // length, width, height, metres

  void AppendBoxes(double t, uint16_t instance, std::vector<Box>* boxes) const;
};

// A cart (issue 24's unknown mover): a large box on castors with a push handle, labelled
// background, so no model card and no network calls it movable; only its motion and depth give
// it away. It is pushed from stop to stop along a closed list of stops (world x, y), waiting
// dwell_s at each, with a smooth start and stop (a half-cosine speed profile peaking at
// max_speed): it stands still long enough to be mapped, then moves off, as a pushed cart does.
// Its heading stays fixed (pushed sideways along a row, not steered).
struct Cart {
  std::vector<Eigen::Vector2d> stops;
  std::vector<double> dwell_s;                            // seconds at each stop (one per stop)
  double max_speed = 0.7;                                 // m/s at the middle of each leg
  double heading = 0.0;                                   // radians from +x, fixed
  int side = 0, top = 0, frame = 0;                       // textures: sides, top, frame/castors
  Eigen::Vector3d size = Eigen::Vector3d(1.1, 0.7, 1.0);  // length, width, height of the box

  // Ground position of the cart's centre at time t (seconds; cyclic over the stops).
  Eigen::Vector2d PositionAt(double t) const;
  void AppendBoxes(double t, uint16_t instance, std::vector<Box>* boxes) const;
};

enum class ActorKind { kPerson, kCar, kCart };

struct Actor {
  uint16_t instance = 0;
  ActorKind kind = ActorKind::kPerson;
  Person person = Person::Seated({}, Eigen::Vector2d::Zero(), 0.0, 0.48, 0.0);
  Car car;
  Cart cart;
  void AppendBoxes(double t, std::vector<Box>* boxes) const;
  void AppendMeshes(double t, std::vector<Mesh>* meshes) const;
};

// A scene: static boxes and actors.
struct World {
  std::vector<Box> static_boxes;
  std::vector<Actor> actors;
  uint16_t next_instance = 1;

  // All boxes at time t.
  std::vector<Box> BoxesAt(double t) const;
  // All meshes (skinned people) at time t.
  std::vector<Mesh> MeshesAt(double t) const;
  // Instance ids of actors whose boxes moved by more than 0.5 mm between t - dt and t: these
  // pixels are "moving" in the frame at t.
  std::vector<uint16_t> MovingInstances(double t, double dt) const;
};

}  // namespace moslam::synth
