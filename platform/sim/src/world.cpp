// The procedural world: street grid (or ring highway), buildings, street furniture, cars, pedestrians,
// and every object's trajectory. Everything is drawn from one seeded RNG in a fixed order.
#include "world.hpp"

#include <algorithm>
#include <cmath>

#include "beslam/common/error.hpp"

namespace beslam::sim::detail {
namespace {

float smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return static_cast<float>(t * t * (3 - 2 * t));
}

// Rounded rectangle polyline, starting at the middle of the south side; counter-clockwise heads east.
std::vector<Vec2d> roundedRect(double x0, double y0, double x1, double y1, double r, bool clockwise, double spacing) {
  std::vector<Vec2d> pts;
  r = std::min({r, 0.5 * (x1 - x0) - 0.01, 0.5 * (y1 - y0) - 0.01});
  auto line = [&](Vec2d a, Vec2d b) {
    const double len = (b - a).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / spacing)));
    for (int i = 0; i < n; ++i) pts.push_back(a + (b - a) * (static_cast<double>(i) / n));
  };
  auto arc = [&](Vec2d c, double a0) {
    const int n = std::max(2, static_cast<int>(std::ceil(r * M_PI / 2 / spacing)));
    for (int i = 0; i < n; ++i) {
      const double a = a0 + (M_PI / 2) * i / n;
      pts.push_back(c + r * Vec2d(std::cos(a), std::sin(a)));
    }
  };
  const double xm = 0.5 * (x0 + x1);
  line({xm, y0}, {x1 - r, y0});
  arc({x1 - r, y0 + r}, -M_PI / 2);
  line({x1, y0 + r}, {x1, y1 - r});
  arc({x1 - r, y1 - r}, 0);
  line({x1 - r, y1}, {x0 + r, y1});
  arc({x0 + r, y1 - r}, M_PI / 2);
  line({x0, y1 - r}, {x0, y0 + r});
  arc({x0 + r, y0 + r}, M_PI);
  line({x0 + r, y0}, {xm, y0});
  if (clockwise) std::reverse(pts.begin() + 1, pts.end());
  return pts;
}

struct Footprint {
  double x, y, c, s, hl, hw;
};

bool overlap(const Footprint& a, const Footprint& b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double ra = std::hypot(a.hl, a.hw), rb = std::hypot(b.hl, b.hw);
  if (dx * dx + dy * dy > (ra + rb) * (ra + rb)) return false;
  const double axes[4][2] = {{a.c, a.s}, {-a.s, a.c}, {b.c, b.s}, {-b.s, b.c}};
  for (const auto& ax : axes) {
    const double d = std::abs(dx * ax[0] + dy * ax[1]);
    const double pa = a.hl * std::abs(a.c * ax[0] + a.s * ax[1]) + a.hw * std::abs(-a.s * ax[0] + a.c * ax[1]);
    const double pb = b.hl * std::abs(b.c * ax[0] + b.s * ax[1]) + b.hw * std::abs(-b.s * ax[0] + b.c * ax[1]);
    if (d > pa + pb) return false;
  }
  return true;
}

Vec3f v3(double x, double y, double z) {
  return Vec3f(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
}

}  // namespace

void Chunk::finish() {
  for (const auto& t : tris)
    for (const Vec3f* p : {&t.a, &t.b, &t.c}) {
      bmin = bmin.cwiseMin(*p);
      bmax = bmax.cwiseMax(*p);
    }
}

Vec3f kittiFromIso(const Vec3f& p) { return Vec3f(p.x(), -p.z(), p.y()); }

void addQuad(std::vector<Tri>& out, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Vec3f& p3,
             std::uint16_t material, std::int32_t param, const Vec3f& u_axis, float u0, const Vec3f& v_axis, float v0) {
  Tri t;
  t.U = Vec4f(u_axis.x(), u_axis.y(), u_axis.z(), u0);
  t.V = Vec4f(v_axis.x(), v_axis.y(), v_axis.z(), v0);
  t.material = material;
  t.param = param;
  t.a = p0, t.b = p1, t.c = p2;
  out.push_back(t);
  t.a = p0, t.b = p2, t.c = p3;
  out.push_back(t);
}

// Axis-aligned box; every face mapped with its two in-plane axes (metres).
void addBox(std::vector<Tri>& out, const Vec3f& lo, const Vec3f& hi, std::uint16_t material, std::int32_t param) {
  const Vec3f X(1, 0, 0), Y(0, 1, 0), Z(0, 0, 1);
  const float x0 = lo.x(), y0 = lo.y(), z0 = lo.z(), x1 = hi.x(), y1 = hi.y(), z1 = hi.z();
  addQuad(out, {x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}, material, param, X, 0, Z, 0);   // -y
  addQuad(out, {x1, y1, z0}, {x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}, material, param, -X, 0, Z, 0);  // +y
  addQuad(out, {x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1}, material, param, Y, 0, Z, 0);   // +x
  addQuad(out, {x0, y1, z0}, {x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, material, param, -Y, 0, Z, 0);  // -x
  addQuad(out, {x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}, material, param, X, 0, Y, 0);   // top
  addQuad(out, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0}, {x0, y0, z0}, material, param, X, 0, Y, 0);   // bottom
}

// Planar triangle with texture axes taken from its own plane.
static void addTriPlanar(std::vector<Tri>& out, const Vec3f& a, const Vec3f& b, const Vec3f& c, std::uint16_t m,
                         int param) {
  Vec3f n = (b - a).cross(c - a);
  if (n.norm() < 1e-9f) return;
  n.normalize();
  Vec3f u = std::abs(n.z()) < 0.9f ? Vec3f(0, 0, 1).cross(n).normalized() : Vec3f(1, 0, 0);
  Vec3f v = n.cross(u).normalized();
  Tri t;
  t.a = a, t.b = b, t.c = c;
  t.U = Vec4f(u.x(), u.y(), u.z(), 0);
  t.V = Vec4f(v.x(), v.y(), v.z(), 0);
  t.material = m;
  t.param = param;
  out.push_back(t);
}

// A tree crown round c: an octahedron subdivided once, its vertices pushed out to a radius jittered
// (by tseed) about cr, stretched sx horizontally and sz vertically.
static void addCrown(std::vector<Tri>& out, const Vec3f& c, float cr, float sx, float sz, std::uint32_t tseed) {
  const Vec3f ax[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  const int faces[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  auto vert = [&](Vec3f dir) {
    dir.normalize();
    const std::uint32_t key =
        static_cast<std::uint32_t>(std::lround(dir.x() * 1000) * 73856093 ^ std::lround(dir.y() * 1000) * 19349663 ^
                                   std::lround(dir.z() * 1000) * 83492791);
    const float rr = cr * (0.8f + 0.4f * hashf(tseed, key, 7));
    return Vec3f(c.x() + dir.x() * rr * sx, c.y() + dir.y() * rr * sx, c.z() + dir.z() * rr * sz);
  };
  for (const auto& f : faces) {
    const Vec3f A = ax[f[0]], Bv = ax[f[1]], C = ax[f[2]];
    const Vec3f ab = (A + Bv) * 0.5f, bc = (Bv + C) * 0.5f, ca = (C + A) * 0.5f;
    const Vec3f sub[4][3] = {{A, ab, ca}, {ab, Bv, bc}, {ca, bc, C}, {ab, bc, ca}};
    for (const auto& s3 : sub)
      addTriPlanar(out, vert(s3[0]), vert(s3[1]), vert(s3[2]), M_LEAVES, static_cast<int>(tseed & 0xffff));
  }
}

// Extrudes a convex side profile (x, z) across y in [-hw, hw]; caps map (x, z), the rim maps (along, y).
static void addPrism(std::vector<Tri>& out, const std::vector<std::pair<float, float>>& prof, float hw,
                     std::uint16_t cap_material, std::uint16_t rim_material, int param, std::uint16_t front_material,
                     std::uint16_t back_material, std::uint16_t top_material) {
  const int n = static_cast<int>(prof.size());
  for (int i = 1; i + 1 < n; ++i) {  // caps (profile counter-clockwise seen from +y)
    Tri t;
    t.material = cap_material;
    t.param = param;
    t.U = Vec4f(1, 0, 0, 0);
    t.V = Vec4f(0, 0, 1, 0);
    t.a = {prof[0].first, hw, prof[0].second};
    t.b = {prof[i].first, hw, prof[i].second};
    t.c = {prof[i + 1].first, hw, prof[i + 1].second};
    out.push_back(t);
    t.a = {prof[0].first, -hw, prof[0].second};
    t.b = {prof[i + 1].first, -hw, prof[i + 1].second};
    t.c = {prof[i].first, -hw, prof[i].second};
    out.push_back(t);
  }
  for (int i = 0; i < n; ++i) {
    const auto& p = prof[i];
    const auto& q = prof[(i + 1) % n];
    const Vec3f a(p.first, -hw, p.second), b(q.first, -hw, q.second), c(q.first, hw, q.second),
        d(p.first, hw, p.second);
    Vec3f e = Vec3f(q.first - p.first, 0, q.second - p.second);
    if (e.norm() < 1e-6f) continue;
    e.normalize();
    const Vec3f nrm(e.z(), 0, -e.x());  // outward for a counter-clockwise profile in (x, z)
    std::uint16_t m = rim_material;
    if (nrm.x() > 0.7f)
      m = front_material;
    else if (nrm.x() < -0.7f)
      m = back_material;
    else if (nrm.z() > 0.7f)
      m = top_material;
    else if (nrm.z() < -0.7f)
      m = rim_material;
    addQuad(out, a, b, c, d, m, param, e, -e.dot(a), Vec3f(0, 1, 0), 0);
  }
}

std::vector<Tri> buildCarMesh(CarShape shape, double length, double width, double height, int style_index, CarStyle& st,
                              const CarProfile* profile) {
  const float l = static_cast<float>(length), w = static_cast<float>(width), h = static_cast<float>(height);
  struct Shape {
    float hb, wb, rf, rr, rb;
  };
  // Per CarShape, in its declaration order (Sedan, Hatchback, Suv, Van, Wagon).
  static constexpr Shape kShapes[] = {{0.60f, 0.20f, 0.02f, -0.22f, -0.33f},
                                      {0.60f, 0.22f, 0.05f, -0.38f, -0.48f},
                                      {0.58f, 0.24f, 0.10f, -0.45f, -0.49f},
                                      {0.48f, 0.44f, 0.32f, -0.48f, -0.50f},
                                      {0.60f, 0.19f, 0.03f, -0.46f, -0.49f}};
  Shape s = kShapes[static_cast<int>(shape)];
  if (profile) {
    if (!(profile->hb > 0 && profile->hb < 1 && profile->x_rb < profile->x_rr && profile->x_rr < profile->x_rf &&
          profile->x_rf < profile->x_wb && profile->x_rb >= -0.5 && profile->x_wb <= 0.5))
      throw Error("car mesh: profile fractions out of order or range");
    s = {static_cast<float>(profile->hb), static_cast<float>(profile->x_wb), static_cast<float>(profile->x_rf),
         static_cast<float>(profile->x_rr), static_cast<float>(profile->x_rb)};
  }
  st.l = l, st.w = w, st.h = h;
  st.hb = s.hb * h;
  st.x_wb = s.wb * l, st.x_rf = s.rf * l, st.x_rr = s.rr * l, st.x_rb = s.rb * l;
  st.wheel_r = shape == CarShape::Van || shape == CarShape::Suv ? 0.36f : 0.31f;
  const float clr = st.wheel_r * 0.55f;
  const float hb = st.hb;
  std::vector<Tri> out;
  // Lower body: chamfered nose and tail.
  const float nose = shape == CarShape::Van ? 0.10f : 0.28f;
  std::vector<std::pair<float, float>> body = {{-l / 2 + 0.05f, clr}, {l / 2 - 0.05f, clr}, {l / 2, clr + 0.15f},
                                               {l / 2, hb - 0.18f},   {l / 2 - nose, hb},   {-l / 2 + 0.12f, hb},
                                               {-l / 2, hb - 0.10f},  {-l / 2, clr + 0.12f}};
  addPrism(out, body, w / 2, M_CAR_BODY, M_CAR_BODY, style_index, M_CAR_FRONT, M_CAR_REAR, M_CAR_BODY);
  // Cabin: trapezoid, slightly narrower; a fraction of a millimetre above the body top.
  const float cw = w / 2 * (shape == CarShape::Van ? 0.97f : 0.86f);
  std::vector<std::pair<float, float>> cabin = {{st.x_rb, hb}, {st.x_wb, hb}, {st.x_rf, h}, {st.x_rr, h}};
  std::vector<Tri> cab;
  addPrism(cab, cabin, cw, M_CAR_CABIN, M_CAR_GLASS, style_index, M_CAR_GLASS, M_CAR_GLASS, M_CAR_BODY);
  for (auto& t : cab) {  // the cabin floor is hidden inside the body
    if (t.a.z() < hb + 1e-4f && t.b.z() < hb + 1e-4f && t.c.z() < hb + 1e-4f) continue;
    out.push_back(t);
  }
  // Wheels: octagonal prisms, outer face just outside the body side.
  const float wx = l / 2 - std::max(0.65f, 0.19f * l);
  const float r = st.wheel_r, tw = 0.22f;
  for (int ix = 0; ix < 2; ++ix)
    for (int iy = 0; iy < 2; ++iy) {
      const float cx = ix ? wx : -wx;
      const float side = iy ? 1.f : -1.f;
      const float yo = side * (w / 2 + 0.004f), yi = side * (w / 2 - tw);
      std::vector<Vec3f> rim_o, rim_i;
      for (int k = 0; k < 8; ++k) {
        const float a = static_cast<float>(k * M_PI / 4 + M_PI / 8);
        rim_o.push_back({cx + r * std::cos(a), yo, r + r * std::sin(a)});
        rim_i.push_back({cx + r * std::cos(a), yi, r + r * std::sin(a)});
      }
      for (int k = 1; k + 1 < 8; ++k) {
        Tri t;
        t.material = M_TYRE;
        t.param = style_index;
        t.U = Vec4f(1, 0, 0, -cx);
        t.V = Vec4f(0, 0, 1, -r);
        if (side > 0)
          t.a = rim_o[0], t.b = rim_o[k + 1], t.c = rim_o[k];
        else
          t.a = rim_o[0], t.b = rim_o[k], t.c = rim_o[k + 1];
        out.push_back(t);
      }
      for (int k = 0; k < 8; ++k) {
        const int k2 = (k + 1) % 8;
        addQuad(out, rim_o[k], rim_o[k2], rim_i[k2], rim_i[k], M_TYRE, -1 - style_index, Vec3f(0, 1, 0), 0,
                Vec3f(0, 0, 1), 0);
      }
    }
  return out;
}

}  // namespace beslam::sim::detail

namespace beslam::sim {
using namespace detail;

static_assert(static_cast<int>(CarShape::Wagon) == static_cast<int>(CarShapeClass::Wagon) &&
                  static_cast<int>(CarShape::Van) == static_cast<int>(CarShapeClass::Van),
              "CarShapeClass mirrors CarShape");

const char* carShapeName(CarShapeClass shape) {
  static const char* kNames[] = {"sedan", "hatchback", "suv", "van", "wagon"};
  return kNames[static_cast<int>(shape)];
}

CarProfile defaultCarProfile(CarShapeClass shape) {
  CarStyle st;
  buildCarMesh(static_cast<CarShape>(shape), 1.0, 1.0, 1.0, 0, st);
  CarProfile p;
  p.hb = st.hb, p.x_wb = st.x_wb, p.x_rf = st.x_rf, p.x_rr = st.x_rr, p.x_rb = st.x_rb;
  return p;
}

CarMesh carMesh(CarShapeClass shape, double length, double width, double height, const CarProfile* profile) {
  if (!(length > 0 && width > 0 && height > 0 && length < 100 && width < 100 && height < 100))
    throw Error("car mesh: size must be positive and finite");
  CarStyle st;
  const std::vector<Tri> tris = buildCarMesh(static_cast<CarShape>(shape), length, width, height, 0, st, profile);
  CarMesh mesh;
  mesh.vertices.reserve(tris.size() * 3);
  mesh.faces.reserve(tris.size());
  for (const Tri& t : tris) {
    const int i = static_cast<int>(mesh.vertices.size());
    mesh.vertices.push_back(t.a.cast<double>());
    mesh.vertices.push_back(t.b.cast<double>());
    mesh.vertices.push_back(t.c.cast<double>());
    mesh.faces.push_back({i, i + 1, i + 2});
  }
  return mesh;
}

CarSizeRange sequenceSizeRange(CarShapeClass shape) {
  // The ranges World::placeObjects draws from (newCar), per CarShapeClass in declaration order.
  static constexpr CarSizeRange kRanges[] = {{4.4, 4.9, 1.74, 1.85, 1.40, 1.50},
                                             {3.8, 4.25, 1.68, 1.78, 1.45, 1.55},
                                             {4.4, 4.9, 1.84, 1.95, 1.65, 1.80},
                                             {4.8, 5.4, 1.9, 2.0, 1.9, 2.2},
                                             {4.55, 4.9, 1.76, 1.85, 1.45, 1.55}};
  return kRanges[static_cast<int>(shape)];
}

double World::roadHalfWidth() const {
  return config.world.lanes_per_direction * config.world.lane_width + (config.world.parking_lanes ? 2.2 : 0.0);
}

double World::parkingLaneOffset() const { return roadHalfWidth() - 1.1; }

int World::addRoute(int i0, int j0, int i1, int j1, bool clockwise, double lateral) {
  const double R = config.world.corner_radius;
  // Right of the heading is outward when counter-clockwise, inward when clockwise.
  const double d = clockwise ? -lateral : lateral;
  auto pts = roundedRect(X_[i0] - d, Y_[j0] - d, X_[i1] + d, Y_[j1] + d, R + d, clockwise, 4.0);
  paths.emplace_back(pts, true);
  return static_cast<int>(paths.size()) - 1;
}

World::World(const SynthConfig& cfg) : config(cfg) {
  if (config.objects.stop_and_go > 0 && !config.world.parking_lanes)
    throw Error("synth config: key 'objects.stop_and_go': needs world.parking_lanes: true");
  Rng rng(mixSeed(config.seed, 1));
  const auto& wc = config.world;
  for (int i = 0; i <= wc.blocks_x; ++i) X_.push_back(i * wc.block_x);
  for (int j = 0; j <= wc.blocks_y; ++j) Y_.push_back(j * wc.block_y);
  if (wc.type == "highway")
    buildHighway(rng);
  else
    buildUrban(rng);

  // Ego: loop round the centre block in the rightmost lane.
  const int ex = wc.blocks_x / 2, ey = wc.blocks_y / 2;
  const double lane0 = (wc.lanes_per_direction - 0.5) * wc.lane_width;
  ego_path = addRoute(ex, ey, ex + 1, ey + 1, config.ego.clockwise, lane0);
  loop_length = paths[ego_path].length();
  ego_profile = Profile(paths[ego_path], config.ego.speed_kmh / 3.6, config.ego.max_lateral_accel, 1.5, -1, -1);
  ego_s0 = config.ego.start_fraction * loop_length;
  T_cam_velo.setIdentity();
  Eigen::Matrix3d R;
  R << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  T_cam_velo.linear() = R;
  T_cam_velo.translation() = Eigen::Vector3d(0, -(config.lidar.mount_height - config.camera.mount_height), -0.27);
  T_sim_cam0 = T_sim_cam(0);
  placeObjects(rng);
}

// ---------------------------------------------------------------------------------------------------
// Urban street grid.

// A block of the urban grid (pavement from x0, y0 to x1, y1) and which of its sides carry buildings.
struct World::Block {
  double x0, y0, x1, y1;
  bool sides[4];
};

// The road surface of one street segment from `start` along the unit axis `dir`, in 20 m tiles.
void World::addStreetTiles(int street, Vec2d start, Vec2d dir, double len) {
  const double hw = roadHalfWidth();
  const Vec2d left(-dir.y(), dir.x());
  const int n = std::max(1, static_cast<int>(std::ceil(len / 20.0)));
  for (int k = 0; k < n; ++k) {
    const double a = len * k / n, b = len * (k + 1) / n;
    Chunk ch;
    const Vec2d p0 = start + dir * a - left * hw, p1 = start + dir * b - left * hw;
    const Vec2d p2 = start + dir * b + left * hw, p3 = start + dir * a + left * hw;
    const Vec3f ua = v3(dir.x(), dir.y(), 0), va = v3(left.x(), left.y(), 0);
    addQuad(ch.tris, v3(p0.x(), p0.y(), 0), v3(p1.x(), p1.y(), 0), v3(p2.x(), p2.y(), 0), v3(p3.x(), p3.y(), 0), M_ROAD,
            street, ua, static_cast<float>(-dir.dot(start)), va, static_cast<float>(-left.dot(start)));
    ch.finish();
    chunks.push_back(std::move(ch));
  }
}

// Streets (one segment between two intersections, horizontal then vertical) and intersections.
void World::buildStreets(Rng& rng) {
  const auto& wc = config.world;
  const double hw = roadHalfWidth();
  const int ex = wc.blocks_x / 2, ey = wc.blocks_y / 2;

  // One street and its segment from `start` along the unit axis `dir` (length in metres, between two
  // intersections); `ego` where the ego's loop runs along it.
  auto addStreet = [&](double length, const Vec2d& start, const Vec2d& dir, bool ego) {
    Street st;
    st.length = static_cast<float>(length);
    st.lanes = wc.lanes_per_direction;
    st.lane_w = static_cast<float>(wc.lane_width);
    st.parking_w = wc.parking_lanes ? 2.2f : 0.f;
    st.crosswalk_start = st.crosswalk_end = true;
    st.seed = static_cast<std::uint32_t>(rng.next());
    streets.push_back(st);
    Segment seg;
    seg.street = static_cast<int>(streets.size()) - 1;
    seg.start = start;
    seg.dir = dir;
    seg.length = st.length;
    seg.ego = ego;
    addStreetTiles(seg.street, seg.start, seg.dir, seg.length);
    segments_.push_back(seg);
  };
  // Streets: horizontal (along x) then vertical (along y), one segment between two intersections.
  for (int j = 0; j <= wc.blocks_y; ++j)
    for (int i = 0; i < wc.blocks_x; ++i)
      addStreet(X_[i + 1] - X_[i] - 2 * hw, Vec2d(X_[i] + hw, Y_[j]), Vec2d(1, 0), i == ex && (j == ey || j == ey + 1));
  for (int i = 0; i <= wc.blocks_x; ++i)
    for (int j = 0; j < wc.blocks_y; ++j)
      addStreet(Y_[j + 1] - Y_[j] - 2 * hw, Vec2d(X_[i], Y_[j] + hw), Vec2d(0, 1), j == ey && (i == ex || i == ex + 1));
  // Intersections.
  for (int i = 0; i <= wc.blocks_x; ++i)
    for (int j = 0; j <= wc.blocks_y; ++j) {
      Chunk ch;
      const float x0 = static_cast<float>(X_[i] - hw), x1 = static_cast<float>(X_[i] + hw);
      const float y0 = static_cast<float>(Y_[j] - hw), y1 = static_cast<float>(Y_[j] + hw);
      addQuad(ch.tris, {x0, y0, 0}, {x1, y0, 0}, {x1, y1, 0}, {x0, y1, 0}, M_ASPHALT, 0, {1, 0, 0}, 0, {0, 1, 0}, 0);
      ch.finish();
      chunks.push_back(std::move(ch));
    }
}

// Blocks: the grid's blocks plus four border strips facing the outer streets.
std::vector<World::Block> World::urbanBlocks() const {
  const auto& wc = config.world;
  const double hw = roadHalfWidth();
  std::vector<Block> blocks;
  for (int i = 0; i < wc.blocks_x; ++i)
    for (int j = 0; j < wc.blocks_y; ++j)
      blocks.push_back({X_[i] + hw, Y_[j] + hw, X_[i + 1] - hw, Y_[j + 1] - hw, {true, true, true, true}});
  const double B = 40.0;
  const double gx0 = X_.front() - hw, gx1 = X_.back() + hw, gy0 = Y_.front() - hw, gy1 = Y_.back() + hw;
  blocks.push_back({gx0 - B, gy0 - B, gx1 + B, gy0, {false, false, true, false}});  // south strip
  blocks.push_back({gx0 - B, gy1, gx1 + B, gy1 + B, {true, false, false, false}});  // north strip
  blocks.push_back({gx0 - B, gy0, gx0, gy1, {false, true, false, false}});          // west strip
  blocks.push_back({gx1, gy0, gx1 + B, gy1, {false, false, false, true}});          // east strip
  return blocks;
}

// Pavement top of a block, tiled.
void World::addPavement(const Block& bk) {
  const float kerb = static_cast<float>(kKerb);
  const int nx = std::max(1, static_cast<int>(std::ceil((bk.x1 - bk.x0) / 20.0)));
  const int ny = std::max(1, static_cast<int>(std::ceil((bk.y1 - bk.y0) / 20.0)));
  for (int a = 0; a < nx; ++a)
    for (int b = 0; b < ny; ++b) {
      Chunk ch;
      const float xa = static_cast<float>(bk.x0 + (bk.x1 - bk.x0) * a / nx),
                  xb = static_cast<float>(bk.x0 + (bk.x1 - bk.x0) * (a + 1) / nx);
      const float ya = static_cast<float>(bk.y0 + (bk.y1 - bk.y0) * b / ny),
                  yb = static_cast<float>(bk.y0 + (bk.y1 - bk.y0) * (b + 1) / ny);
      addQuad(ch.tris, {xa, ya, kerb}, {xb, ya, kerb}, {xb, yb, kerb}, {xa, yb, kerb}, M_PAVEMENT, 0, {1, 0, 0}, 0,
              {0, 1, 0}, 0);
      ch.finish();
      chunks.push_back(std::move(ch));
    }
}

// Kerb face of a block side from corner S along d (length L).
void World::addKerbFace(const Vec2d& S, const Vec2d& d, double L) {
  const float kerb = static_cast<float>(kKerb);
  Chunk ch;
  const int m = std::max(1, static_cast<int>(std::ceil(L / 20.0)));
  for (int q = 0; q < m; ++q) {
    const Vec2d a = S + d * (L * q / m), b = S + d * (L * (q + 1) / m);
    addQuad(ch.tris, v3(a.x(), a.y(), 0), v3(b.x(), b.y(), 0), v3(b.x(), b.y(), kerb), v3(a.x(), a.y(), kerb), M_KERB,
            0, v3(d.x(), d.y(), 0), static_cast<float>(-d.dot(S)), {0, 0, 1}, 0);
  }
  ch.finish();
  chunks.push_back(std::move(ch));
}

// Style of a random building's facades (colours, bricks, floors, windows, shop front); `height` gets its
// height in metres.
Facade World::randomFacade(Rng& rng, int building, double& height) const {
  const auto& wc = config.world;
  Facade f;
  f.building = building;
  f.base = rng.chance(0.45) ? 0 : 1 + rng.index(2);
  static const float palette[][3] = {{0.55f, 0.30f, 0.22f}, {0.70f, 0.58f, 0.42f}, {0.80f, 0.76f, 0.66f},
                                     {0.62f, 0.64f, 0.62f}, {0.74f, 0.52f, 0.38f}, {0.50f, 0.52f, 0.58f},
                                     {0.85f, 0.80f, 0.60f}, {0.66f, 0.44f, 0.40f}, {0.78f, 0.72f, 0.78f}};
  const auto& pc = palette[rng.index(9)];
  const float jit = static_cast<float>(rng.uniform(0.85, 1.12));
  f.colour = Vec3f(pc[0], pc[1], pc[2]) * jit;
  f.frame_colour = rng.chance(0.6) ? Vec3f(0.92f, 0.92f, 0.90f)
                                   : Vec3f(0.25f, 0.22f, 0.20f) * static_cast<float>(rng.uniform(0.8, 1.6));
  f.trim_colour = f.colour * static_cast<float>(rng.uniform(0.55, 0.8));
  f.brick_w = static_cast<float>(rng.uniform(0.22, 0.30));
  f.brick_h = static_cast<float>(rng.uniform(0.065, 0.09));
  f.floor_h = static_cast<float>(rng.uniform(2.7, 3.3));
  f.ground_h = static_cast<float>(rng.uniform(3.2, 4.4));
  f.win_w = static_cast<float>(rng.uniform(0.8, 1.7));
  f.win_h = static_cast<float>(rng.uniform(1.1, 1.9));
  f.win_h = std::min(f.win_h, f.floor_h - 0.9f);
  f.win_sill = static_cast<float>(rng.uniform(0.6, f.floor_h - f.win_h - 0.25));
  f.col_spacing = std::max(f.win_w + 0.5f, static_cast<float>(rng.uniform(1.7, 3.0)));
  f.col_offset = static_cast<float>(rng.uniform(0.0, f.col_spacing));
  f.shop = rng.chance(0.4);
  f.panel_w = static_cast<float>(rng.uniform(2.0, 4.5));
  f.door_w = static_cast<float>(rng.uniform(1.0, 2.2));
  const int floors = std::max(
      1, static_cast<int>(
             std::round((rng.uniform(wc.building_min_height, wc.building_max_height) - f.ground_h) / f.floor_h)));
  height = f.ground_h + floors * f.floor_h + rng.uniform(0.3, 1.2);
  f.height = static_cast<float>(height);
  return f;
}

// Buildings along side k of a block (start corner S, direction d, length L), each with its facades, roof
// and perhaps a front hedge or wall; sides 1 and 3 keep clear of the corner buildings of sides 0 and 2.
// `building` counts the buildings so far.
void World::addBuildings(Rng& rng, int k, const Vec2d& S, const Vec2d& d, double L, int& building) {
  const auto& wc = config.world;
  const double pw = wc.pavement_width;
  const float kerb = static_cast<float>(kKerb);
  const Vec2d n(d.y(), -d.x()), in = -n;
  const double corner_clear = (k % 2 == 1) ? pw + wc.building_setback_max + 17.0 : 0.0;
  double along = corner_clear + (k % 2 == 0 ? 0.0 : rng.uniform(0, 3));
  const double end = L - corner_clear;
  while (along < end - 6.0) {
    if (along > corner_clear + 1.0 && rng.chance(wc.building_gap_probability)) along += rng.uniform(2.0, 6.0);
    double width = rng.uniform(8.0, 22.0);
    if (end - (along + width) < 6.0) width = end - along;
    if (width < 5.0) break;
    const double setback = rng.uniform(0.0, wc.building_setback_max);
    const double depth = rng.uniform(10.0, 16.0);
    // Style.
    double height;
    const Facade f = randomFacade(rng, building, height);
    // Footprint corners (front-left, front-right, back-right, back-left seen from the street).
    const double fo = pw + setback, ba = fo + depth;
    const Vec2d c0 = S + d * along + in * fo, c1 = S + d * (along + width) + in * fo;
    const Vec2d c2 = S + d * (along + width) + in * ba, c3 = S + d * along + in * ba;
    const Vec2d corners[4] = {c0, c1, c2, c3};
    Chunk ch;
    for (int w = 0; w < 4; ++w) {
      const Vec2d a = corners[w], b = corners[(w + 1) % 4];
      // Face outward normal is to the right of a->b? Corners go counter-clockwise seen from outside the
      // front, so a->b runs left to right when seen from outside for every wall.
      Facade fw = f;
      fw.length = static_cast<float>((b - a).norm());
      fw.seed = static_cast<std::uint32_t>(rng.next());
      fw.door_face = w == 0;
      fw.door_u = static_cast<float>(rng.uniform(1.0, std::max(1.1, fw.length - fw.door_w - 1.0)));
      if (w != 0) fw.shop = false;
      facades.push_back(fw);
      const int fid = static_cast<int>(facades.size()) - 1;
      const Vec2d ud = (b - a).normalized();
      addQuad(ch.tris, v3(a.x(), a.y(), kerb), v3(b.x(), b.y(), kerb), v3(b.x(), b.y(), height),
              v3(a.x(), a.y(), height), M_FACADE, fid, v3(ud.x(), ud.y(), 0), static_cast<float>(-ud.dot(a)), {0, 0, 1},
              -kerb);
    }
    const float hh = static_cast<float>(height);
    addQuad(ch.tris, v3(c0.x(), c0.y(), hh), v3(c1.x(), c1.y(), hh), v3(c2.x(), c2.y(), hh), v3(c3.x(), c3.y(), hh),
            M_ROOF, building, {1, 0, 0}, 0, {0, 1, 0}, 0);
    // A hedge or low wall in the front garden when the building stands back from the pavement.
    if (setback > 1.0 && rng.chance(0.6)) {
      const double hd = std::min(0.9, setback - 0.2), hh = rng.uniform(0.6, 1.3);
      const Vec2d h0 = S + d * (along + 0.3) + in * (pw + 0.1),
                  h1 = S + d * (along + width - 0.3) + in * (pw + 0.1 + hd);
      const bool wall = rng.chance(0.3);
      Chunk hc;
      addBox(hc.tris, v3(std::min(h0.x(), h1.x()), std::min(h0.y(), h1.y()), kKerb),
             v3(std::max(h0.x(), h1.x()), std::max(h0.y(), h1.y()), kKerb + hh), wall ? M_FENCE : M_LEAVES,
             wall ? 0 : static_cast<int>(rng.next() & 0xffff));
      hc.finish();
      chunks.push_back(std::move(hc));
    }
    ch.finish();
    chunks.push_back(std::move(ch));
    ++building;
    along += width;
  }
}

// Street furniture along one side of a grid block (start corner S, direction d, length L): lamps, signs
// and trees near the kerb, kept apart from each other.
void World::addStreetFurniture(Rng& rng, const Vec2d& S, const Vec2d& d, double L) {
  const auto& wc = config.world;
  const float kerb = static_cast<float>(kKerb);
  const Vec2d n(d.y(), -d.x()), in = -n;
  std::vector<double> used;
  auto clear = [&](double u, double gap) {
    for (double x : used)
      if (std::abs(x - u) < gap) return false;
    return true;
  };
  // Lamps.
  for (double u = rng.uniform(8, 20); u < L - 8; u += rng.uniform(24, 36)) {
    used.push_back(u);
    const Vec2d p = S + d * u + in * 0.45;
    Chunk ch;
    const float px = static_cast<float>(p.x()), py = static_cast<float>(p.y());
    addBox(ch.tris, {px - 0.08f, py - 0.08f, kerb}, {px + 0.08f, py + 0.08f, 6.5f}, M_POLE, 0);
    const Vec2d q = p + n * 1.3;
    const float qx = static_cast<float>(q.x()), qy = static_cast<float>(q.y());
    addBox(ch.tris, {std::min(px, qx) - 0.05f, std::min(py, qy) - 0.05f, 6.3f},
           {std::max(px, qx) + 0.05f, std::max(py, qy) + 0.05f, 6.42f}, M_POLE, 0);
    addBox(ch.tris, {qx - 0.25f, qy - 0.25f, 6.05f}, {qx + 0.25f, qy + 0.25f, 6.3f}, M_SIGN_BACK, 0);
    ch.finish();
    chunks.push_back(std::move(ch));
  }
  // Signs near the far corner, facing traffic that approaches the next intersection.
  for (int q = 0; q < 2; ++q) {
    if (!rng.chance(0.7)) continue;
    const double u = q == 0 ? L - rng.uniform(5, 9) : rng.uniform(0.3, 0.7) * L;
    if (!clear(u, 2.0)) continue;
    used.push_back(u);
    const Vec2d p = S + d * u + in * 0.5;
    SignStyle sg;
    sg.kind = rng.index(5);
    sg.seed = static_cast<std::uint32_t>(rng.next());
    signs.push_back(sg);
    const int sid = static_cast<int>(signs.size()) - 1;
    Chunk ch;
    const float px = static_cast<float>(p.x()), py = static_cast<float>(p.y());
    const float top = static_cast<float>(rng.uniform(2.4, 2.9));
    addBox(ch.tris, {px - 0.04f, py - 0.04f, kerb}, {px + 0.04f, py + 0.04f, top + 0.3f}, M_POLE, 0);
    // The plate faces +d (towards cars driving in -d on this side) or the street.
    const Vec2d face = q == 0 ? d : n;
    const Vec2d side(-face.y(), face.x());
    const float hs = sg.kind == 4 ? 0.45f : 0.32f;
    const Vec2d f0 = p + face * 0.06;
    const Vec3f sa = v3(side.x(), side.y(), 0);
    const Vec2d a = f0 - side * hs, b = f0 + side * hs;
    addQuad(ch.tris, v3(b.x(), b.y(), top), v3(a.x(), a.y(), top), v3(a.x(), a.y(), top + 2 * hs),
            v3(b.x(), b.y(), top + 2 * hs), M_SIGN, sid, -sa, static_cast<float>(side.dot(f0)), {0, 0, 1}, -(top + hs));
    const Vec2d f1 = p + face * 0.05;
    const Vec2d a1 = f1 - side * hs, b1 = f1 + side * hs;
    addQuad(ch.tris, v3(a1.x(), a1.y(), top), v3(b1.x(), b1.y(), top), v3(b1.x(), b1.y(), top + 2 * hs),
            v3(a1.x(), a1.y(), top + 2 * hs), M_SIGN_BACK, sid, sa, 0, {0, 0, 1}, 0);
    ch.finish();
    chunks.push_back(std::move(ch));
  }
  // Trees.
  if (wc.tree_spacing > 0) {
    for (double u = rng.uniform(4, wc.tree_spacing); u < L - 6; u += wc.tree_spacing * rng.uniform(0.7, 1.3)) {
      if (!clear(u, 2.5) || !rng.chance(0.85)) continue;
      used.push_back(u);
      const Vec2d p = S + d * u + in * 1.0;
      Chunk ch;
      const float px = static_cast<float>(p.x()), py = static_cast<float>(p.y());
      const float tr = static_cast<float>(rng.uniform(0.10, 0.18));
      const float th = static_cast<float>(rng.uniform(2.3, 3.4));
      addBox(ch.tris, {px - tr, py - tr, kerb}, {px + tr, py + tr, th + 0.3f}, M_BARK, 0);
      const float cr = static_cast<float>(rng.uniform(1.4, 2.6));
      const Vec3f c(px, py, th + cr * 0.85f);
      const std::uint32_t tseed = static_cast<std::uint32_t>(rng.next());
      const float sx = static_cast<float>(rng.uniform(0.85, 1.15)), sz = static_cast<float>(rng.uniform(0.8, 1.2));
      addCrown(ch.tris, c, cr, sx, sz, tseed);
      ch.finish();
      chunks.push_back(std::move(ch));
    }
  }
}

void World::buildUrban(Rng& rng) {
  buildStreets(rng);
  const std::vector<Block> blocks = urbanBlocks();
  int building = 0;
  for (const Block& bk : blocks) {
    raised.push_back({bk.x0, bk.y0, bk.x1, bk.y1});
    addPavement(bk);
    // Sides: start corner, direction, outward normal (counter-clockwise traversal).
    const Vec2d S[4] = {{bk.x0, bk.y0}, {bk.x1, bk.y0}, {bk.x1, bk.y1}, {bk.x0, bk.y1}};
    const Vec2d D[4] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    const double L[4] = {bk.x1 - bk.x0, bk.y1 - bk.y0, bk.x1 - bk.x0, bk.y1 - bk.y0};
    for (int k = 0; k < 4; ++k) {
      addKerbFace(S[k], D[k], L[k]);
      if (!bk.sides[k]) continue;
      addBuildings(rng, k, S[k], D[k], L[k], building);
    }
    // Street furniture on grid blocks: trees, lamps and signs near the kerb.
    if (!(bk.sides[0] && bk.sides[1] && bk.sides[2] && bk.sides[3])) continue;
    for (int k = 0; k < 4; ++k) addStreetFurniture(rng, S[k], D[k], L[k]);
  }
}

// ---------------------------------------------------------------------------------------------------
// Highway: one big ring road (two carriageways split by a median), verges, guard rails, noise walls,
// trees and signs; far buildings.

namespace {

// The point `off` metres left of the ring at arc length s, and the ring's direction there.
void ringPointAt(const Path& ring, double s, double off, Vec2d& p, Vec2d& dir) {
  double h, k;
  ring.at(s, p, h, k);
  dir = Vec2d(std::cos(h), std::sin(h));
  const Vec2d left(-dir.y(), dir.x());
  p += left * off;
}

}  // namespace

// The highway's ribbons along the ring (length L) in 4 m quads, five to a chunk: both carriageways,
// verges, guard rails, noise walls and the median.
void World::addHighwayRibbons(const Path& ring, double L) {
  const double hw = roadHalfWidth();
  const int n = static_cast<int>(std::ceil(L / 4.0));
  auto pointAt = [&](double s, double off, Vec2d& p, Vec2d& dir) { ringPointAt(ring, s, off, p, dir); };
  const double verge = hw + 3.0, wall = hw + 9.0;
  for (int c = 0; c < n; c += 5) {
    Chunk road, side;
    for (int q = c; q < std::min(n, c + 5); ++q) {
      const double s0 = L * q / n, s1 = L * (q + 1) / n;
      Vec2d d0, d1;
      // Road ribbon: u = s, v = lateral offset (left positive).
      auto ribbon = [&](std::vector<Tri>& out, double o0, double o1, double z0, double z1, std::uint16_t m,
                        bool road_uv) {
        Vec2d p00, p01, p10, p11;
        pointAt(s0, o0, p00, d0);
        pointAt(s1, o0, p01, d1);
        pointAt(s0, o1, p10, d0);
        pointAt(s1, o1, p11, d1);
        const Vec3f A = v3(p00.x(), p00.y(), z0), B = v3(p01.x(), p01.y(), z0), C = v3(p11.x(), p11.y(), z1),
                    D = v3(p10.x(), p10.y(), z1);
        // Affine (u, v) from the local frame at s0: exact enough per 4 m quad.
        const Vec2d dm = (d0 + d1).normalized(), lm(-dm.y(), dm.x());
        Vec2d c0;
        double hh, kk;
        ring.at(s0, c0, hh, kk);
        if (road_uv) {
          addQuad(out, A, B, C, D, m, 0, v3(dm.x(), dm.y(), 0), static_cast<float>(s0 - dm.dot(c0)),
                  v3(lm.x(), lm.y(), 0), static_cast<float>(-lm.dot(c0)));
        } else {
          const Vec3f ud = (B - A).normalized();
          const Vec3f vd = (D - A).normalized();
          addQuad(out, A, B, C, D, m, 0, ud, -ud.dot(A) + static_cast<float>(s0), vd, -vd.dot(A));
        }
      };
      ribbon(road.tris, -hw, hw, 0, 0, M_ROAD, true);
      ribbon(side.tris, hw, verge, 0, 0, M_GRASS, false);
      ribbon(side.tris, -verge, -hw, 0, 0, M_GRASS, false);
      ribbon(side.tris, verge, wall, 0, 0, M_GRASS, false);
      ribbon(side.tris, -wall, -verge, 0, 0, M_GRASS, false);
      // Guard rails (vertical strips) just outside the hard shoulder, and noise walls further out.
      ribbon(side.tris, hw + 0.8, hw + 0.8, 0.45, 0.8, M_RAIL, false);
      ribbon(side.tris, -hw - 0.8, -hw - 0.8, 0.8, 0.45, M_RAIL, false);
      ribbon(side.tris, wall, wall, 0.0, 4.0, M_WALL, false);
      ribbon(side.tris, -wall, -wall, 4.0, 0.0, M_WALL, false);
      ribbon(side.tris, -0.35, 0.35, 0.0, 0.0, M_GRASS, false);
      ribbon(side.tris, 0.0, 0.0, 0.3, 1.0, M_RAIL, false);
    }
    road.finish();
    side.finish();
    chunks.push_back(std::move(road));
    chunks.push_back(std::move(side));
  }
}

// Poles and signs along both verges, trees behind the walls.
void World::addHighwayRoadside(Rng& rng, const Path& ring, double L) {
  const auto& wc = config.world;
  const double hw = roadHalfWidth();
  auto pointAt = [&](double s, double off, Vec2d& p, Vec2d& dir) { ringPointAt(ring, s, off, p, dir); };
  const double wall = hw + 9.0;
  for (double s = rng.uniform(10, 40); s < L - 10; s += rng.uniform(40, 70)) {
    for (int sideSign = -1; sideSign <= 1; sideSign += 2) {
      Vec2d p, dir;
      pointAt(s, sideSign * (hw + 2.0), p, dir);
      Chunk ch;
      const float px = static_cast<float>(p.x()), py = static_cast<float>(p.y());
      addBox(ch.tris, {px - 0.09f, py - 0.09f, 0}, {px + 0.09f, py + 0.09f, 9.0f}, M_POLE, 0);
      if (rng.chance(0.35)) {
        SignStyle sg;
        sg.kind = 4;
        sg.seed = static_cast<std::uint32_t>(rng.next());
        signs.push_back(sg);
        const int sid = static_cast<int>(signs.size()) - 1;
        const Vec2d face = -dir * sideSign;  // towards traffic on that side (right-hand traffic)
        const Vec2d sd(-face.y(), face.x());
        const Vec2d f0 = p + face * 0.12;
        const float hs = 1.2f;
        const Vec2d a = f0 - sd * hs, b = f0 + sd * hs;
        addQuad(ch.tris, v3(b.x(), b.y(), 3.2), v3(a.x(), a.y(), 3.2), v3(a.x(), a.y(), 4.6), v3(b.x(), b.y(), 4.6),
                M_SIGN, sid, v3(-sd.x(), -sd.y(), 0), static_cast<float>(sd.dot(f0)), {0, 0, 1}, -3.9f);
      }
      ch.finish();
      chunks.push_back(std::move(ch));
    }
  }
  if (wc.tree_spacing > 0)
    for (double s = rng.uniform(0, wc.tree_spacing); s < L; s += wc.tree_spacing * rng.uniform(0.6, 1.4)) {
      for (int sideSign = -1; sideSign <= 1; sideSign += 2) {
        Vec2d p, dir;
        pointAt(s, sideSign * (wall + rng.uniform(3, 12)), p, dir);
        Chunk ch;
        const float px = static_cast<float>(p.x()), py = static_cast<float>(p.y());
        const float th = static_cast<float>(rng.uniform(2.5, 4.0)), cr = static_cast<float>(rng.uniform(2.0, 3.5));
        addBox(ch.tris, {px - 0.18f, py - 0.18f, 0}, {px + 0.18f, py + 0.18f, th + 0.3f}, M_BARK, 0);
        const Vec3f c(px, py, th + cr * 0.85f);
        const float sz = static_cast<float>(rng.uniform(0.9, 1.4));
        const std::uint32_t tseed = static_cast<std::uint32_t>(rng.next());
        addCrown(ch.tris, c, cr, 1.0f, sz, tseed);
        ch.finish();
        chunks.push_back(std::move(ch));
      }
    }
}

// Ground inside and outside the ring, then a few far buildings round it.
void World::addHighwayGroundAndFarBuildings(Rng& rng, const Path& ring, double L) {
  const double hw = roadHalfWidth();
  auto pointAt = [&](double s, double off, Vec2d& p, Vec2d& dir) { ringPointAt(ring, s, off, p, dir); };
  const double wall = hw + 9.0;
  // Ground inside and outside the ring.
  {
    Chunk ch;
    const float x0 = static_cast<float>(X_.front() - 400), x1 = static_cast<float>(X_.back() + 400);
    const float y0 = static_cast<float>(Y_.front() - 400), y1 = static_cast<float>(Y_.back() + 400);
    // A grass plane slightly below the road so the ribbons win everywhere they exist.
    const int m = 12;
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) {
        const float xa = x0 + (x1 - x0) * a / m, xb = x0 + (x1 - x0) * (a + 1) / m;
        const float ya = y0 + (y1 - y0) * b / m, yb = y0 + (y1 - y0) * (b + 1) / m;
        addQuad(ch.tris, {xa, ya, -0.05f}, {xb, ya, -0.05f}, {xb, yb, -0.05f}, {xa, yb, -0.05f}, M_GRASS, 0, {1, 0, 0},
                0, {0, 1, 0}, 0);
      }
    ch.finish();
    chunks.push_back(std::move(ch));
  }
  for (int q = 0; q < 40; ++q) {  // distant buildings
    const double s = rng.uniform(0, L);
    const int sideSign = rng.chance(0.5) ? 1 : -1;
    Vec2d p, dir;
    pointAt(s, sideSign * (wall + rng.uniform(30, 80)), p, dir);
    Facade f;
    f.base = rng.index(3);
    f.colour = Vec3f(0.6f, 0.6f, 0.6f) * static_cast<float>(rng.uniform(0.8, 1.3));
    f.frame_colour = Vec3f(0.3f, 0.3f, 0.3f);
    f.trim_colour = f.colour * 0.7f;
    f.floor_h = 3.2f;
    f.ground_h = 4.0f;
    f.height = static_cast<float>(rng.uniform(8, 30));
    const float w = static_cast<float>(rng.uniform(15, 40)), dd = static_cast<float>(rng.uniform(12, 25));
    const float px = static_cast<float>(p.x()), py = static_cast<float>(p.y());
    Chunk ch;
    const Vec2d cs[4] = {
        {px - w / 2, py - dd / 2}, {px + w / 2, py - dd / 2}, {px + w / 2, py + dd / 2}, {px - w / 2, py + dd / 2}};
    for (int k = 0; k < 4; ++k) {
      Facade fw = f;
      const Vec2d a = cs[k], b = cs[(k + 1) % 4];
      fw.length = static_cast<float>((b - a).norm());
      fw.seed = static_cast<std::uint32_t>(rng.next());
      facades.push_back(fw);
      const Vec2d ud = (b - a).normalized();
      addQuad(ch.tris, v3(a.x(), a.y(), 0), v3(b.x(), b.y(), 0), v3(b.x(), b.y(), f.height), v3(a.x(), a.y(), f.height),
              M_FACADE, static_cast<int>(facades.size()) - 1, v3(ud.x(), ud.y(), 0), static_cast<float>(-ud.dot(a)),
              {0, 0, 1}, 0);
    }
    ch.finish();
    chunks.push_back(std::move(ch));
  }
}

void World::buildHighway(Rng& rng) {
  const auto& wc = config.world;
  const double R = wc.corner_radius;
  // The ring follows the same rounded rectangle as the routes (street lines 0 and blocks).
  const int i0 = 0, j0 = 0, i1 = wc.blocks_x, j1 = wc.blocks_y;
  auto centre = roundedRect(X_[i0], Y_[j0], X_[i1], Y_[j1], R, false, 5.0);
  Path ring(centre, true);
  const double L = ring.length();
  Street st;
  st.length = static_cast<float>(L);
  st.lanes = wc.lanes_per_direction;
  st.lane_w = static_cast<float>(wc.lane_width);
  st.parking_w = 0;
  st.median = true;
  st.seed = static_cast<std::uint32_t>(rng.next());
  streets.push_back(st);
  addHighwayRibbons(ring, L);
  addHighwayRoadside(rng, ring, L);
  addHighwayGroundAndFarBuildings(rng, ring, L);
}

// ---------------------------------------------------------------------------------------------------
// Objects and trajectories.

double World::groundHeight(double x, double y) const {
  double best = 0;
  for (const auto& r : raised) {
    // Distance inside the rectangle (negative outside); a 0.3 m ramp across the kerb line.
    const double inside = std::min({x - r.x0, r.x1 - x, y - r.y0, r.y1 - y});
    best = std::max(best, kKerb * smoothstep(-0.15, 0.15, inside));
  }
  return best;
}

Pose2 World::egoPose(double t) const {
  Pose2 p;
  Vec2d xy;
  double h, k;
  const double s = ego_s0 + ego_profile.sAt(t);
  paths[ego_path].at(s, xy, h, k);
  p.x = xy.x(), p.y = xy.y(), p.yaw = h, p.speed = ego_profile.speedAt(t), p.walked = s;
  return p;
}

Eigen::Isometry3d World::T_sim_cam(double t) const {
  Vec2d xy;
  double h, k;
  const double s = ego_s0 + ego_profile.sAt(t);
  paths[ego_path].at(s, xy, h, k);
  const double v = ego_profile.speedAt(t);
  const double a_lat = v * v * k;
  const double dv = ego_profile.speedAt(t + 0.05) - ego_profile.speedAt(t - 0.05);
  const double a_long = dv / 0.1;
  const double ph = static_cast<double>(mixSeed(config.seed, 9) % 1000) / 1000.0 * 2 * M_PI;
  const double deg = M_PI / 180.0;
  const double pitch = config.ego.pitch_amplitude_deg * deg *
                           (0.6 * std::sin(2 * M_PI * 0.37 * t + ph) + 0.4 * std::sin(2 * M_PI * 1.13 * t + 2 * ph)) -
                       0.15 * deg * a_long;
  const double roll =
      -config.ego.roll_per_accel_deg * deg * a_lat + 0.05 * deg * std::sin(2 * M_PI * 0.71 * t + 3 * ph);
  const double bounce = 0.008 * std::sin(2 * M_PI * 1.3 * t + ph);
  const Eigen::Vector3d fwd(std::cos(h), std::sin(h), 0), right(std::sin(h), -std::cos(h), 0), down(0, 0, -1);
  Eigen::Matrix3d R;
  R.col(0) = right;
  R.col(1) = down;
  R.col(2) = fwd;
  R = R * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()).toRotationMatrix() *
      Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = Eigen::Vector3d(xy.x(), xy.y(), config.camera.mount_height + bounce);
  return T;
}

Pose2 World::objectPose(const Object& o, double t) const {
  Pose2 p;
  Vec2d xy = Vec2d::Zero();
  double h = o.yaw, k = 0;
  switch (o.kind) {
    case Object::Kind::Static:
      p.x = o.x, p.y = o.y, p.yaw = o.yaw;
      return p;
    case Object::Kind::Loop: {
      const double s = o.s_offset + o.profile.sAt(t);
      paths[o.path].at(s, xy, h, k);
      p.speed = o.profile.speedAt(t);
      p.walked = s;
      break;
    }
    case Object::Kind::PullOut: {
      const double tau = t - o.t_wait;
      const double s = tau > 0 ? o.profile.sAt(tau) : 0.0;
      paths[o.path].at(s, xy, h, k);
      p.speed = tau > 0 ? o.profile.speedAt(tau) : 0.0;
      break;
    }
    case Object::Kind::ParkIn: {
      const double s = o.profile.sAt(t);
      paths[o.path].at(s, xy, h, k);
      p.speed = o.profile.speedAt(t);
      if (s >= paths[o.path].length() - 1e-9) p.speed = 0;
      break;
    }
    case Object::Kind::PedLoop: {
      const double s = o.s_offset + o.walk_speed * t;
      paths[o.path].at(s, xy, h, k);
      p.speed = o.walk_speed;
      p.walked = o.walk_speed * t;
      break;
    }
    case Object::Kind::PedCross: {
      const double len = (o.b - o.a).norm();
      const double walk = len / o.walk_speed;
      const double period = o.wait_a + walk + o.wait_b + walk;
      const double tt = t + o.phase;
      const double cycles = std::floor(tt / period);
      double tau = tt - cycles * period;
      const Vec2d dir = (o.b - o.a) / len;
      double pos;
      double walked = cycles * 2 * len;
      if (tau < o.wait_a) {
        pos = 0, h = std::atan2(dir.y(), dir.x());
      } else if ((tau -= o.wait_a) < walk) {
        pos = tau * o.walk_speed, h = std::atan2(dir.y(), dir.x()), p.speed = o.walk_speed, walked += pos;
      } else if ((tau -= walk) < o.wait_b) {
        pos = len, h = std::atan2(-dir.y(), -dir.x()), walked += len;
      } else {
        tau -= o.wait_b;
        pos = len - tau * o.walk_speed, h = std::atan2(-dir.y(), -dir.x()), p.speed = o.walk_speed,
        walked += len + tau * o.walk_speed;
      }
      xy = o.a + dir * pos;
      p.walked = walked;
      break;
    }
  }
  p.x = xy.x(), p.y = xy.y(), p.yaw = h;
  if (o.kind == Object::Kind::PedLoop) {
    const Vec2d left(-std::sin(h), std::cos(h));
    p.x += left.x() * o.lateral, p.y += left.y() * o.lateral;
  }
  if (o.info.behaviour == Behaviour::Pedestrian) p.z = groundHeight(p.x, p.y);
  return p;
}

Eigen::Isometry3d World::T_sim_obj(const Object& o, double t) const {
  const Pose2 p = objectPose(o, t);
  Eigen::Matrix3d M;  // KITTI object axes in ISO object coordinates: x, -z, y
  M << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(p.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * M;
  T.translation() = Eigen::Vector3d(p.x, p.y, p.z);
  return T;
}

void World::objectTris(const Object& o, double t, std::vector<Tri>& out) const {
  out.clear();
  if (o.info.behaviour != Behaviour::Pedestrian) {
    out = o.mesh;
    return;
  }
  // Walking figure inside the box l x w x h (x forward, y left, z up).
  const Pose2 p = objectPose(o, t);
  const float H = static_cast<float>(o.info.height);
  const float phase = static_cast<float>(p.walked / 0.7 * M_PI);
  const float swing = p.speed > 0.05 ? 0.45f * std::sin(phase) : 0.f;
  const float hip = 0.50f * H, shoulder = 0.81f * H, headb = 0.86f * H;
  auto limb = [&](float y, float top, float len, float thick, float angle, std::uint16_t m) {
    // A box hanging from (0, y, top), rotated about the y axis by `angle`.
    const float c = std::cos(angle), s = std::sin(angle);
    Vec3f lo(-thick / 2, y - thick / 2, -len), hi(thick / 2, y + thick / 2, 0);
    std::vector<Tri> box;
    addBox(box, lo, hi, m, o.style);
    for (auto& tr : box) {
      for (Vec3f* v : {&tr.a, &tr.b, &tr.c}) {
        const float x = v->x(), z = v->z();
        *v = Vec3f(c * x + s * z, v->y(), -s * x + c * z + top);
      }
      out.push_back(tr);
    }
  };
  limb(0.1f, hip, hip, 0.15f, swing, M_PED_TROUSERS);
  limb(-0.1f, hip, hip, 0.15f, -swing, M_PED_TROUSERS);
  addBox(out, {-0.12f, -0.2f, hip}, {0.12f, 0.2f, shoulder}, M_PED_SHIRT, o.style);
  limb(0.26f, shoulder, 0.30f * H, 0.10f, -0.6f * swing, M_PED_SHIRT);
  limb(-0.26f, shoulder, 0.30f * H, 0.10f, 0.6f * swing, M_PED_SHIRT);
  addBox(out, {-0.1f, -0.09f, headb}, {0.11f, 0.09f, H}, M_PED_SKIN, o.style);
}

// The state placeObjects' stages share: the footprints over time of the ego and of every object accepted
// so far (an object is placed only where its footprints overlap none of them).
struct World::Placement {
  struct Track {
    std::vector<Footprint> fp;
  };
  Placement(World& world, Rng& r) : w(world), rng(r) {}

  World& w;
  Rng& rng;
  int steps = 0;
  double dt = 0;
  std::vector<Track> tracks;  // accepted objects' footprints over time (static: one entry)
  Track egoTrack;
  int next_id = 1;

  // The object's footprints at every step (static: one entry).
  Track footprints(const Object& o) const {
    Track tr;
    const bool ped = o.info.behaviour == Behaviour::Pedestrian;
    const double hl = ped ? 0.35 : o.info.length / 2 + 0.3, hwid = ped ? 0.35 : o.info.width / 2 + 0.2;
    const int n = o.kind == Object::Kind::Static ? 0 : steps;
    for (int i = 0; i <= n; ++i) {
      const Pose2 p = w.objectPose(o, i * dt);
      tr.fp.push_back({p.x, p.y, std::cos(p.yaw), std::sin(p.yaw), hl, hwid});
    }
    return tr;
  }
  // Whether track a overlaps an accepted object's (or, with checkEgo, the ego's) at any step.
  bool collides(const Track& a, bool checkEgo) const {
    auto at = [](const Track& t, int i) -> const Footprint& { return t.fp.size() == 1 ? t.fp[0] : t.fp[i]; };
    for (int i = 0; i <= steps; ++i) {
      if (checkEgo && overlap(at(a, i), egoTrack.fp[i])) return true;
      for (const auto& b : tracks)
        if (!(a.fp.size() == 1 && b.fp.size() == 1) && overlap(at(a, i), at(b, i))) return true;
      if (a.fp.size() == 1) {  // a static object only needs one pass against movers and the ego
        bool anyMover = checkEgo;
        for (const auto& b : tracks) anyMover = anyMover || b.fp.size() > 1;
        if (!anyMover) break;
      }
    }
    if (a.fp.size() == 1)
      for (const auto& b : tracks)
        if (b.fp.size() == 1 && overlap(a.fp[0], b.fp[0])) return true;
    return false;
  }
  // Gives o the next track id and moves it into the world.
  void accept(Object& o, const Track& tr) {
    o.info.track_id = next_id++;
    w.objects.push_back(std::move(o));
    tracks.push_back(tr);
  }
  // Accepts o where its track is free; else undoes what making it added.
  template <class Undo>
  bool place(Object& o, const Undo& undo) {
    const Track tr = footprints(o);
    if (collides(tr, true)) {
      undo();
      return false;
    }
    accept(o, tr);
    return true;
  }
  // Places `count` objects, each with up to `attempts` calls of tryOne(n, attempt), which returns whether
  // it placed object n (a failed try undoes what it added); returns how many were placed.
  template <class TryOne>
  static int placeEach(int count, int attempts, const TryOne& tryOne) {
    int placed = 0;
    for (int n = 0; n < count; ++n)
      for (int attempt = 0; attempt < attempts; ++attempt)
        if (tryOne(n, attempt)) {
          ++placed;
          break;
        }
    return placed;
  }
};

int World::randomSegment(Rng& rng, double ego_share) const {
  std::vector<int> egoSegs;
  for (std::size_t i = 0; i < segments_.size(); ++i)
    if (segments_[i].ego) egoSegs.push_back(static_cast<int>(i));
  return (!egoSegs.empty() && rng.chance(ego_share)) ? egoSegs[rng.index(static_cast<int>(egoSegs.size()))]
                                                     : rng.index(static_cast<int>(segments_.size()));
}

// A car of a random shape, size and colour with behaviour b (its style appended to car_styles).
Object World::newCar(Placement& pl, Behaviour b) {
  Rng& rng = pl.rng;
  Object o;
  o.info.behaviour = b;
  const double r = rng.uniform();
  double l, w, h;
  if (r < 0.30)
    o.shape = CarShape::Sedan, l = rng.uniform(4.4, 4.9), w = rng.uniform(1.74, 1.85), h = rng.uniform(1.40, 1.50),
    o.info.shape = "sedan";
  else if (r < 0.52)
    o.shape = CarShape::Hatchback, l = rng.uniform(3.8, 4.25), w = rng.uniform(1.68, 1.78), h = rng.uniform(1.45, 1.55),
    o.info.shape = "hatchback";
  else if (r < 0.70)
    o.shape = CarShape::Wagon, l = rng.uniform(4.55, 4.9), w = rng.uniform(1.76, 1.85), h = rng.uniform(1.45, 1.55),
    o.info.shape = "wagon";
  else if (r < 0.87)
    o.shape = CarShape::Suv, l = rng.uniform(4.4, 4.9), w = rng.uniform(1.84, 1.95), h = rng.uniform(1.65, 1.80),
    o.info.shape = "suv";
  else
    o.shape = CarShape::Van, l = rng.uniform(4.8, 5.4), w = rng.uniform(1.9, 2.0), h = rng.uniform(1.9, 2.2),
    o.info.shape = "van";
  o.info.type = o.shape == CarShape::Van ? "Van" : "Car";
  CarStyle cs;
  static const float colours[][3] = {{0.85f, 0.85f, 0.86f}, {0.08f, 0.08f, 0.09f}, {0.55f, 0.56f, 0.58f},
                                     {0.62f, 0.08f, 0.07f}, {0.10f, 0.18f, 0.45f}, {0.75f, 0.75f, 0.72f},
                                     {0.15f, 0.32f, 0.18f}, {0.80f, 0.55f, 0.10f}, {0.35f, 0.22f, 0.15f},
                                     {0.30f, 0.45f, 0.62f}, {0.92f, 0.90f, 0.82f}, {0.45f, 0.05f, 0.20f}};
  const auto& c = colours[rng.index(12)];
  cs.colour = Vec3f(c[0], c[1], c[2]) * static_cast<float>(rng.uniform(0.9, 1.08));
  cs.seed = static_cast<std::uint32_t>(rng.next());
  cs.metallic = static_cast<float>(rng.uniform(0.0, 1.0));
  cs.plate_seed = static_cast<int>(rng.next() & 0x7fffffff);
  o.style = static_cast<int>(car_styles.size());
  o.mesh = buildCarMesh(o.shape, l, w, h, o.style, cs);
  car_styles.push_back(cs);
  o.info.length = l, o.info.width = w + 0.008, o.info.height = h;
  return o;
}

// Picks a random loop route; kind 0: the ego's loop, same direction; 1: ego's loop, opposite; 2: other.
int World::randomRoute(Placement& pl, int kind, int lane, bool& clockwise) {
  Rng& rng = pl.rng;
  const auto& wc = config.world;
  const int ex = wc.blocks_x / 2, ey = wc.blocks_y / 2;
  const bool highway = wc.type == "highway";
  int i0 = ex, j0 = ey, i1 = ex + 1, j1 = ey + 1;
  clockwise = config.ego.clockwise;
  if (kind == 1) clockwise = !clockwise;
  if (kind == 2 && !highway) {
    do {
      i0 = rng.index(wc.blocks_x), i1 = i0 + 1 + rng.index(wc.blocks_x - i0);
      j0 = rng.index(wc.blocks_y), j1 = j0 + 1 + rng.index(wc.blocks_y - j0);
    } while (wc.blocks_x * wc.blocks_y > 1 && i0 == ex && j0 == ey && i1 == ex + 1 && j1 == ey + 1);
    clockwise = rng.chance(0.5);
  }
  if (highway) i0 = 0, j0 = 0, i1 = wc.blocks_x, j1 = wc.blocks_y;
  const double lat = (lane + 0.5) * wc.lane_width;
  return addRoute(i0, j0, i1, j1, clockwise, lat);
}

// Stop-and-go cars (placed first: they reserve their parking spots); returns how many were placed.
int World::placeStopAndGo(Placement& pl) {
  Rng& rng = pl.rng;
  const auto& oc = config.objects;
  const auto& wc = config.world;
  const double T = config.frames / config.rate_hz;
  const double parkLat = parkingLaneOffset();
  return Placement::placeEach(oc.stop_and_go, 60, [&](int, int attempt) {
    const std::size_t np = paths.size(), ns = car_styles.size();
    auto rollback = [&] {
      paths.resize(np, paths.front());
      car_styles.resize(ns);
    };
    Object o = newCar(pl, Behaviour::StopAndGo);
    bool cw;
    const int kind = attempt < 30 ? rng.index(2) : 2;
    const int route = randomRoute(pl, kind, wc.lanes_per_direction - 1, cw);
    const Path& rp = paths[route];
    const double v = rng.uniform(oc.driving_speed_kmh_min, oc.driving_speed_kmh_max) / 3.6;
    const bool pullOut = rng.chance(0.5);
    const double extra = parkLat - (wc.lanes_per_direction - 0.5) * wc.lane_width;
    const double sp = rng.uniform(0, rp.length());
    // The spot must be on a straight stretch.
    bool straight = true;
    for (double q = -25; q <= 25; q += 2.5) {
      Vec2d xy;
      double h, k;
      rp.at(sp + q, xy, h, k);
      straight = straight && std::abs(k) < 1e-3;
    }
    if (!straight) {
      rollback();
      return false;
    }
    double len, twait = 0;
    if (pullOut) {
      twait = rng.uniform(0.15, 0.55) * T;
      len = v * (T - twait) + 40;
    } else {
      len = std::max(40.0, v * rng.uniform(0.3, 0.7) * T);
    }
    std::vector<Vec2d> ctrl;
    for (double q = 0; q <= len + 1e-9; q += 2.0) {
      const double s = pullOut ? sp + q : sp - len + q;
      Vec2d xy;
      double h, k;
      rp.at(s, xy, h, k);
      const double e = pullOut ? extra * (1 - smoothstep(4, 20, q)) : extra * smoothstep(len - 22, len - 5, q);
      xy += Vec2d(std::sin(h), -std::cos(h)) * e;
      ctrl.push_back(xy);
    }
    paths.emplace_back(ctrl, false);
    o.path = static_cast<int>(paths.size()) - 1;
    o.kind = pullOut ? Object::Kind::PullOut : Object::Kind::ParkIn;
    o.t_wait = twait;
    o.profile = pullOut ? Profile(paths[o.path], v, 2.5, 1.5, 0.0, -1) : Profile(paths[o.path], v, 2.5, 1.5, -1, 0.0);
    // A car that parks must arrive well within the sequence, so both of its phases are seen.
    if (!pullOut && o.profile.lapTime() > 0.85 * T) {
      rollback();
      return false;
    }
    return pl.place(o, rollback);
  });
}

// Parked cars in the parking lanes, mostly along the ego's loop; returns how many were placed.
int World::placeParked(Placement& pl) {
  if (!config.world.parking_lanes || segments_.empty()) return 0;
  Rng& rng = pl.rng;
  const auto& oc = config.objects;
  const double parkLat = parkingLaneOffset();
  return Placement::placeEach(oc.parked, 80, [&](int, int) {
    Object o = newCar(pl, Behaviour::Parked);
    const Segment& seg = segments_[randomSegment(rng, 0.75)];
    const int side = rng.index(2);
    const double margin = 7.0 + o.info.length / 2;
    if (seg.length < 2 * margin) {
      car_styles.pop_back();
      return false;
    }
    const double u = rng.uniform(margin, seg.length - margin);
    const Vec2d left(-seg.dir.y(), seg.dir.x());
    const Vec2d xy = seg.start + seg.dir * u + left * (side ? parkLat : -parkLat);
    o.kind = Object::Kind::Static;
    o.x = xy.x(), o.y = xy.y();
    o.yaw = std::atan2(seg.dir.y(), seg.dir.x()) + (side ? M_PI : 0.0) + rng.uniform(-0.03, 0.03);
    // Keep the kerb side tight; jitter the lateral position a little.
    return pl.place(o, [&] { car_styles.pop_back(); });
  });
}

// Driving cars: loops in and against the ego direction (overtaking where there is a second lane), and
// round other blocks, which cross the ego's streets; returns how many were placed.
int World::placeDriving(Placement& pl) {
  Rng& rng = pl.rng;
  const auto& oc = config.objects;
  const auto& wc = config.world;
  const double egoSpeed = config.ego.speed_kmh / 3.6;
  return Placement::placeEach(oc.driving, 80, [&](int n, int) {
    Object o = newCar(pl, Behaviour::Driving);
    const int kind = n % 3 == 0 ? 0 : (n % 3 == 1 ? 1 : 2);
    int lane = rng.index(wc.lanes_per_direction);
    double v = rng.uniform(oc.driving_speed_kmh_min, oc.driving_speed_kmh_max) / 3.6;
    if (kind == 0 && wc.lanes_per_direction >= 2)
      lane = wc.lanes_per_direction - 2, v = std::max(v, egoSpeed * rng.uniform(1.3, 1.6));
    else if (kind == 0)
      v = egoSpeed;  // same lane as the ego: keeps its distance
    bool cw;
    const int route = randomRoute(pl, kind, lane, cw);
    o.path = route;
    o.kind = Object::Kind::Loop;
    o.profile = Profile(paths[route], v, 2.5, 1.5, -1, -1);
    o.s_offset = rng.uniform(0, paths[route].length());
    const auto undo = [&] {
      paths.pop_back();
      car_styles.pop_back();
    };
    return pl.place(o, undo);
  });
}

// Pedestrians: walking round blocks on the pavement, or crossing streets at the crosswalks; returns how
// many were placed.
int World::placePedestrians(Placement& pl) {
  Rng& rng = pl.rng;
  const auto& oc = config.objects;
  const auto& wc = config.world;
  const double hw = roadHalfWidth();
  const int ex = wc.blocks_x / 2, ey = wc.blocks_y / 2;
  const bool highway = wc.type == "highway";
  return Placement::placeEach(highway ? 0 : oc.pedestrians, 80, [&](int n, int) {
    Object o;
    o.info.behaviour = Behaviour::Pedestrian;
    o.info.type = "Pedestrian";
    o.info.shape = "pedestrian";
    o.info.height = rng.uniform(1.55, 1.92);
    o.info.length = 0.8, o.info.width = 0.6;
    PedStyle ps;
    ps.shirt = Vec3f(static_cast<float>(rng.uniform(0.05, 0.9)), static_cast<float>(rng.uniform(0.05, 0.9)),
                     static_cast<float>(rng.uniform(0.05, 0.9)));
    ps.trousers = Vec3f(0.12f, 0.13f, 0.2f) * static_cast<float>(rng.uniform(0.6, 2.5));
    const float sk = static_cast<float>(rng.uniform(0.35, 0.85));
    ps.skin = Vec3f(sk * 0.75f, sk * 0.85f, sk);
    o.style = static_cast<int>(ped_styles.size());
    o.walk_speed = rng.uniform(1.05, 1.6);
    bool added_path = false;
    if (n % 2 == 0 || segments_.empty()) {
      int bi = ex, bj = ey;
      if (rng.chance(0.4)) bi = rng.index(wc.blocks_x), bj = rng.index(wc.blocks_y);
      const double inset = rng.uniform(1.2, wc.pavement_width - 0.6);
      auto pts = roundedRect(X_[bi] + hw + inset, Y_[bj] + hw + inset, X_[bi + 1] - hw - inset, Y_[bj + 1] - hw - inset,
                             2.0, rng.chance(0.5), 2.0);
      paths.emplace_back(pts, true);
      added_path = true;
      o.path = static_cast<int>(paths.size()) - 1;
      o.kind = Object::Kind::PedLoop;
      o.s_offset = rng.uniform(0, paths.back().length());
    } else {
      const Segment& seg = segments_[randomSegment(rng, 0.7)];
      const double u = rng.chance(0.5) ? rng.uniform(2.0, 4.0) : seg.length - rng.uniform(2.0, 4.0);
      const Vec2d left(-seg.dir.y(), seg.dir.x());
      const Vec2d c = seg.start + seg.dir * u;
      const double reach = hw + rng.uniform(0.8, 1.8);
      const bool flip = rng.chance(0.5);
      o.a = c + left * (flip ? reach : -reach);
      o.b = c - left * (flip ? reach : -reach);
      o.kind = Object::Kind::PedCross;
      o.wait_a = rng.uniform(2, 10), o.wait_b = rng.uniform(2, 10);
      o.phase = rng.uniform(0, 60);
    }
    if (!pl.place(o, [&] {
          if (added_path) paths.pop_back();
        }))
      return false;
    ped_styles.push_back(ps);
    return true;
  });
}

void World::placeObjects(Rng& rng) {
  Placement pl(*this, rng);
  pl.steps = config.frames * 4;
  pl.dt = 1.0 / (config.rate_hz * 4);
  for (int i = 0; i <= pl.steps; ++i) {
    const Pose2 e = egoPose(i * pl.dt);
    const double c = std::cos(e.yaw), s = std::sin(e.yaw);
    // The ego's body plus a safety zone ahead: nothing comes closer than about 8 m in front.
    pl.egoTrack.fp.push_back({e.x + c * 2.25, e.y + s * 2.25, c, s, 5.75, 1.15});
  }
  const int placed_sg = placeStopAndGo(pl);
  const int placed_parked = placeParked(pl);
  const int placed_driving = placeDriving(pl);
  const int placed_peds = placePedestrians(pl);
  count_stop_and_go = placed_sg, count_parked = placed_parked, count_driving = placed_driving,
  count_pedestrians = placed_peds;
}

}  // namespace beslam::sim
