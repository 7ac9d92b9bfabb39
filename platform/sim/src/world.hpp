// Internal: the synthetic world. Frames: "sim" world is x east, y north, z up (metres, road at z = 0);
// object meshes are built in an ISO vehicle frame (x forward, y left, z up, origin at the bottom centre).
// The KITTI world of the outputs is the camera frame at frame 0.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "beslam/sim/car_mesh.hpp"
#include "beslam/sim/synth.hpp"

namespace beslam::sim::detail {

using Vec2d = Eigen::Vector2d;
using Vec3f = Eigen::Vector3f;
using Vec4f = Eigen::Vector4f;

// Seeded RNG with our own distributions (std:: distributions differ between library versions).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : g_(seed) {}
  double uniform() { return static_cast<double>(g_() >> 11) * (1.0 / 9007199254740992.0); }
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  int index(int n) { return static_cast<int>(uniform() * n) % n; }
  bool chance(double p) { return uniform() < p; }
  double normal();
  std::uint64_t next() { return g_(); }

 private:
  std::mt19937_64 g_;
};

inline std::uint32_t hash32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}
inline std::uint32_t hash3(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  return hash32((a * 0x8da6b343U) ^ (b * 0xd8163841U) ^ (c * 0xcb1ab31fU) ^ 0x9e3779b9U);
}
inline float hashf(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  return static_cast<float>(hash3(a, b, c) >> 8) * (1.0f / 16777216.0f);
}
std::uint64_t mixSeed(std::uint64_t seed, std::uint64_t stream);

// Planar path from a control polyline: uniform cubic B-spline (C2), sampled densely, arc-length indexed.
class Path {
 public:
  Path() = default;
  Path(const std::vector<Vec2d>& control, bool closed);
  double length() const { return length_; }
  bool closed() const { return closed_; }
  // s is wrapped on a closed path and clamped on an open one.
  void at(double s, Vec2d& p, double& heading, double& curvature) const;

 private:
  bool closed_ = false;
  double length_ = 0;
  std::vector<double> s_, x_, y_, heading_, curvature_;
};

// Speed along a path: v(s) limited by curvature and acceleration; s(t) by integration.
class Profile {
 public:
  Profile() = default;
  // v_start/v_end < 0 mean "free" (cruise); closed paths are periodic.
  Profile(const Path& path, double v_cruise, double a_lat, double a_long, double v_start, double v_end);
  double sAt(double t) const;  // distance travelled after time t (from s = 0 at t = 0)
  double speedAt(double t) const;
  double lapTime() const { return t_.empty() ? 0 : t_.back(); }
  double length() const { return length_; }

 private:
  bool closed_ = false;
  double length_ = 0;
  std::vector<double> s_, v_, t_;  // grid
};

enum Mat : std::uint16_t {
  M_ROAD,
  M_ASPHALT,
  M_PAVEMENT,
  M_KERB,
  M_FACADE,
  M_ROOF,
  M_BARK,
  M_LEAVES,
  M_POLE,
  M_SIGN,
  M_SIGN_BACK,
  M_GRASS,
  M_WALL,
  M_RAIL,
  M_CAR_BODY,
  M_CAR_CABIN,
  M_CAR_GLASS,
  M_CAR_FRONT,
  M_CAR_REAR,
  M_TYRE,
  M_FENCE,
  M_PED_SHIRT,
  M_PED_TROUSERS,
  M_PED_SKIN,
  M_COUNT
};

// A triangle in its mesh frame; texture coordinates u = U.(p,1), v = V.(p,1) in metres.
struct Tri {
  Vec3f a, b, c;
  Vec4f U, V;
  std::uint16_t material = 0;
  std::int32_t param = 0;  // material parameter: facade, street, sign, car index ...
};

struct Chunk {  // a group of static triangles culled together
  std::vector<Tri> tris;
  Vec3f bmin{1e9f, 1e9f, 1e9f}, bmax{-1e9f, -1e9f, -1e9f};
  void finish();
};

struct Facade {  // one building face
  float length = 0, height = 0;
  std::uint32_t seed = 0;
  int building = 0;
  // style
  int base = 0;  // 0 brick, 1 plaster, 2 concrete panels
  Vec3f colour, frame_colour, trim_colour;
  float brick_w = 0.25f, brick_h = 0.075f;
  float floor_h = 3.0f, ground_h = 3.6f;
  float win_w = 1.2f, win_h = 1.5f, win_sill = 0.9f, col_spacing = 2.6f, col_offset = 0;
  bool shop = false, door_face = false;
  float door_u = 0, door_w = 1.2f;
  float panel_w = 3.0f;
};

struct Street {  // a road stretch: u along, v across from the centreline (metres)
  float length = 0;
  int lanes = 1;
  float lane_w = 3.25f, parking_w = 0.f;
  bool crosswalk_start = false, crosswalk_end = false;
  bool median = false;  // highway: a solid double line and a gap between carriageways
  std::uint32_t seed = 0;
};

struct SignStyle {
  int kind = 0;
  std::uint32_t seed = 0;
};

struct CarStyle {
  Vec3f colour;
  std::uint32_t seed = 0;
  float metallic = 0;
  // Side profile (ISO object frame, metres): body top hb, roof h, windscreen base x_wb, roof front x_rf,
  // roof rear x_rr, rear window base x_rb, wheel radius.
  float l = 4.5f, w = 1.8f, h = 1.5f, hb = 0.9f, x_wb = 0.8f, x_rf = 0.1f, x_rr = -1.0f, x_rb = -1.5f, wheel_r = 0.32f;
  int plate_seed = 0;
};

struct PedStyle {
  Vec3f shirt, trousers, skin;
};

enum class CarShape { Sedan, Hatchback, Suv, Van, Wagon };

// A moving or parked object.
struct Object {
  ObjectInfo info;
  CarShape shape = CarShape::Sedan;
  std::vector<Tri> mesh;  // ISO object frame (cars); pedestrians are built per frame
  int style = 0;          // index into car_styles / ped_styles
  // Motion.
  enum class Kind { Static, Loop, PullOut, ParkIn, PedLoop, PedCross } kind = Kind::Static;
  int path = -1;  // index into World::paths
  Profile profile;
  double s_offset = 0;           // start position on the path (loops)
  double t_wait = 0;             // pull-out: standing until this time
  double x = 0, y = 0, yaw = 0;  // static pose
  // Pedestrian crossing: walks A->B and back with waits.
  Vec2d a{0, 0}, b{0, 0};
  double walk_speed = 1.3, wait_a = 3, wait_b = 3, phase = 0;
  double lateral = 0;  // pedestrians: offset from the path
};

struct Pose2 {
  double x = 0, y = 0, z = 0, yaw = 0, speed = 0, walked = 0;
};

// Mesh helpers (used by the world and the car builder).
void addQuad(std::vector<Tri>& out, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Vec3f& p3,
             std::uint16_t material, std::int32_t param, const Vec3f& u_axis, float u0, const Vec3f& v_axis, float v0);
void addBox(std::vector<Tri>& out, const Vec3f& lo, const Vec3f& hi, std::uint16_t material, std::int32_t param);
// Fills the profile fields of `style` and returns the mesh (ISO object frame) for a car of that shape;
// `profile`, when given, replaces the shape's side-profile fractions (beslam/sim/car_mesh.hpp).
std::vector<Tri> buildCarMesh(CarShape shape, double length, double width, double height, int style_index,
                              CarStyle& style, const CarProfile* profile = nullptr);
Vec3f kittiFromIso(const Vec3f& p);  // (x, y, z) ISO -> (x, -z, y) KITTI object frame

}  // namespace beslam::sim::detail

namespace beslam::sim {
using namespace detail;

class World {
 public:
  explicit World(const SynthConfig& config);

  SynthConfig config;
  std::vector<Chunk> chunks;
  std::vector<Facade> facades;
  std::vector<Street> streets;
  std::vector<SignStyle> signs;
  std::vector<CarStyle> car_styles;
  std::vector<PedStyle> ped_styles;
  std::vector<Path> paths;
  std::vector<Object> objects;
  struct Rect {
    double x0, y0, x1, y1;
  };
  std::vector<Rect> raised;  // pavement areas (z = kerb height)
  static constexpr double kKerb = 0.15;

  // Ego.
  int ego_path = -1;
  Profile ego_profile;
  double ego_s0 = 0;
  Eigen::Isometry3d T_sim_cam0 = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_cam_velo = Eigen::Isometry3d::Identity();
  double loop_length = 0;
  int count_parked = 0, count_driving = 0, count_stop_and_go = 0, count_pedestrians = 0;

  double frameTime(int frame) const { return frame / config.rate_hz; }
  Eigen::Isometry3d T_sim_cam(double t) const;
  Pose2 egoPose(double t) const;
  Pose2 objectPose(const Object& o, double t) const;
  double groundHeight(double x, double y) const;
  // KITTI object frame -> sim world.
  Eigen::Isometry3d T_sim_obj(const Object& o, double t) const;
  // Object triangles (ISO object frame) at time t (animated for pedestrians).
  void objectTris(const Object& o, double t, std::vector<Tri>& out) const;

 private:
  void buildUrban(Rng& rng);
  // buildUrban's stages (world.cpp).
  struct Block;
  void buildStreets(Rng& rng);
  void addStreetTiles(int street, Vec2d start, Vec2d dir, double len);
  std::vector<Block> urbanBlocks() const;
  void addPavement(const Block& bk);
  void addKerbFace(const Vec2d& S, const Vec2d& d, double L);
  Facade randomFacade(Rng& rng, int building, double& height) const;
  void addBuildings(Rng& rng, int k, const Vec2d& S, const Vec2d& d, double L, int& building);
  void addStreetFurniture(Rng& rng, const Vec2d& S, const Vec2d& d, double L);
  void buildHighway(Rng& rng);
  // buildHighway's stages (world.cpp); ring: the road's centreline, L its length.
  void addHighwayRibbons(const Path& ring, double L);
  void addHighwayRoadside(Rng& rng, const Path& ring, double L);
  void addHighwayGroundAndFarBuildings(Rng& rng, const Path& ring, double L);
  void placeObjects(Rng& rng);
  // placeObjects' stages (world.cpp); Placement holds the footprints of what is placed so far.
  struct Placement;
  Object newCar(Placement& pl, Behaviour b);
  int randomRoute(Placement& pl, int kind, int lane, bool& clockwise);
  int placeStopAndGo(Placement& pl);
  int placeParked(Placement& pl);
  int placeDriving(Placement& pl);
  int placePedestrians(Placement& pl);
  // A random street segment: with probability ego_share (where there are any) one bordering the ego's block.
  int randomSegment(Rng& rng, double ego_share) const;
  // Closed route round street lines i0..i1 x j0..j1, `lateral` metres right of the centreline.
  int addRoute(int i0, int j0, int i1, int j1, bool clockwise, double lateral);
  double roadHalfWidth() const;
  // The parking lanes' centre from the street centreline, metres.
  double parkingLaneOffset() const;
  std::vector<double> X_, Y_;  // street centrelines
  struct Segment {             // a street segment between two intersections
    int street = 0;            // index into streets
    Vec2d start, dir;          // centreline start and unit direction (u axis); v axis = left of dir
    double length = 0;
    bool ego = false;                                    // borders the ego's block
    std::vector<std::pair<double, double>> occupied[2];  // parking intervals (u), side 0: v<0, 1: v>0
  };
  std::vector<Segment> segments_;
};

}  // namespace beslam::sim

namespace beslam::sim::detail {
using sim::World;
}  // namespace beslam::sim::detail
