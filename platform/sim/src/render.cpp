// Per-frame rendering: camera (deferred: rasterise ids and 1/z, then shade each pixel once), image
// effects, instance mask, labels, and the LiDAR scan (candidate triangles from four raster faces round
// the sensor, then an exact ray-triangle intersection).
#include <algorithm>
#include <cmath>
#include <map>

#include "beslam/sim/synth.hpp"
#include "raster.hpp"
#include "shade.hpp"
#include "world.hpp"

namespace beslam::sim {
using namespace detail;

namespace {

struct ViewTri {
  Vec3f a, b, c;
  Vec3f n;     // unit normal facing the viewer
  Vec4f U, V;  // texture coordinates as affine functions of the view-frame point
  std::uint16_t material;
  std::int32_t param;
  std::uint16_t instance;
  float light;
};

struct Sphere {
  Vec3f c;
  float r;
};

Sphere chunkSphere(const Chunk& ch) { return {(ch.bmin + ch.bmax) * 0.5f, (ch.bmax - ch.bmin).norm() * 0.5f}; }

// Materials whose meshes are wound outward (boxes, building walls and roofs, ground pieces seen from
// above): their back faces can be skipped. Cars, crowns, signs and ribbons are drawn two-sided.
inline bool closedMaterial(std::uint16_t m) {
  switch (m) {
    case M_FACADE:
    case M_ROOF:
    case M_ROAD:
    case M_ASPHALT:
    case M_PAVEMENT:
    case M_KERB:
    case M_POLE:
    case M_BARK:
    case M_FENCE:
    case M_GRASS:
    case M_PED_SHIRT:
    case M_PED_TROUSERS:
    case M_PED_SKIN:
      return true;
    default:
      return false;
  }
}

// Transforms mesh-frame triangles into a view frame; T_view_mesh maps mesh points into the view.
void appendTris(const std::vector<Tri>& tris, const Eigen::Matrix3f& R, const Vec3f& t, std::uint16_t instance,
                const Vec3f& sun_view, std::vector<ViewTri>& out) {
  for (const Tri& tr : tris) {
    ViewTri v;
    v.a = R * tr.a + t;
    v.b = R * tr.b + t;
    v.c = R * tr.c + t;
    Vec3f n = (v.b - v.a).cross(v.c - v.a);
    const float len = n.norm();
    if (len < 1e-12f) continue;
    n /= len;
    if (n.dot(v.a) > 0) {
      if (closedMaterial(tr.material)) continue;  // back face of a closed, outward-wound surface
      n = -n;
    }
    v.n = n;
    // u = U.xyz . p_mesh + U.w with p_mesh = R^T (p_view - t).
    const Vec3f Ur = R * tr.U.head<3>(), Vr = R * tr.V.head<3>();
    v.U = Vec4f(Ur.x(), Ur.y(), Ur.z(), tr.U.w() - Ur.dot(t));
    v.V = Vec4f(Vr.x(), Vr.y(), Vr.z(), tr.V.w() - Vr.dot(t));
    v.material = tr.material;
    v.param = tr.param;
    v.instance = instance;
    v.light = 0.68f + 0.45f * std::max(0.f, n.dot(sun_view));
    out.push_back(v);
  }
}

bool sphereVisible(const Sphere& s, const Eigen::Matrix3f& R, const Vec3f& t, const float planes[][4], int nplanes,
                   float max_dist) {
  const Vec3f c = R * s.c + t;
  if (c.norm() - s.r > max_dist) return false;
  for (int i = 0; i < nplanes; ++i)
    if (planes[i][0] * c.x() + planes[i][1] * c.y() + planes[i][2] * c.z() + planes[i][3] < -s.r) return false;
  return true;
}

// Frustum side planes (unit normals, through the origin) for a pinhole view.
int frustumPlanes(float W, float H, float fx, float fy, float cx, float cy, float planes[5][4]) {
  auto set = [&](int i, float a, float b, float c) {
    const float n = std::sqrt(a * a + b * b + c * c);
    planes[i][0] = a / n, planes[i][1] = b / n, planes[i][2] = c / n, planes[i][3] = 0;
  };
  set(0, fx, 0, cx + 2);
  set(1, -fx, 0, W + 1 - cx);
  set(2, 0, fy, cy + 2);
  set(3, 0, -fy, H + 1 - cy);
  planes[4][0] = 0, planes[4][1] = 0, planes[4][2] = 1, planes[4][3] = -0.1f;
  return 5;
}

inline std::uint8_t toByte(float x) { return static_cast<std::uint8_t>(std::min(255.f, std::max(0.f, x)) + 0.5f); }

// 2^18 unit-variance noise samples, shared and built once (deterministic).
const std::vector<float>& noiseTable() {
  static const std::vector<float> table = [] {
    std::vector<float> t(1u << 18);
    for (std::size_t i = 0; i < t.size(); ++i) {
      const std::uint32_t h = hash3(static_cast<std::uint32_t>(i), 0x5eedu, 17u);
      const float s = static_cast<float>((h & 255) + ((h >> 8) & 255) + ((h >> 16) & 255) + (h >> 24));
      t[i] = (s - 510.f) / 147.22f;
    }
    return t;
  }();
  return table;
}

inline float gauss(std::uint32_t h) {
  // Irwin-Hall of four bytes: mean 0, unit variance.
  const float s = static_cast<float>((h & 255) + ((h >> 8) & 255) + ((h >> 16) & 255) + (h >> 24));
  return (s - 510.f) / 147.22f;
}

// Per-thread buffers reused between frames (fresh multi-megabyte allocations cost page faults).
struct Scratch {
  RasterTarget cam;
  RasterTarget face[4];
  std::vector<ViewTri> vt, lt;
  cv::Mat lin, tmp;
  std::vector<std::int32_t> stamp;
  std::vector<int> visible;
  std::vector<float> vrow;
};

Scratch& scratch() {
  static thread_local Scratch s;
  return s;
}

bool rayTriangle(const Vec3f& o, const Vec3f& d, const ViewTri& t, float& dist) {
  const Vec3f e1 = t.b - t.a, e2 = t.c - t.a;
  const Vec3f p = d.cross(e2);
  const float det = e1.dot(p);
  if (std::abs(det) < 1e-12f) return false;
  const float inv = 1.f / det;
  const Vec3f s = o - t.a;
  const float u = s.dot(p) * inv;
  const float tol = 1e-4f;
  if (u < -tol || u > 1 + tol) return false;
  const Vec3f q = s.cross(e1);
  const float v = d.dot(q) * inv;
  if (v < -tol || u + v > 1 + tol) return false;
  dist = e2.dot(q) * inv;
  return dist > 0;
}

}  // namespace

Synthesizer::Synthesizer(const SynthConfig& config) : world_(std::make_unique<World>(config)) {
  for (const auto& o : world_->objects) infos_.push_back(o.info);
}
Synthesizer::~Synthesizer() = default;
const SynthConfig& Synthesizer::config() const { return world_->config; }
int Synthesizer::frameCount() const { return world_->config.frames; }

Eigen::Matrix<double, 3, 4> Synthesizer::projection() const {
  const auto& c = world_->config.camera;
  Eigen::Matrix<double, 3, 4> P = Eigen::Matrix<double, 3, 4>::Zero();
  P(0, 0) = c.fx, P(0, 2) = c.cx, P(1, 1) = c.fy, P(1, 2) = c.cy, P(2, 2) = 1;
  return P;
}
Eigen::Isometry3d Synthesizer::T_cam_velo() const { return world_->T_cam_velo; }
Eigen::Isometry3d Synthesizer::T_world_cam(int frame) const {
  return world_->T_sim_cam0.inverse() * world_->T_sim_cam(world_->frameTime(frame));
}

const std::vector<ObjectInfo>& Synthesizer::objects() const { return infos_; }

ObjectState Synthesizer::objectState(int track_id, int frame) const {
  ObjectState st;
  for (const auto& o : world_->objects) {
    if (o.info.track_id != track_id) continue;
    const double t = world_->frameTime(frame);
    st.T_world_obj = world_->T_sim_cam0.inverse() * world_->T_sim_obj(o, t);
    st.speed = world_->objectPose(o, t).speed;
    st.moving = st.speed > 1e-9;
    return st;
  }
  return st;
}

void Synthesizer::objectMesh(int track_id, std::vector<Eigen::Vector3f>& vertices,
                             std::vector<std::array<int, 3>>& faces) const {
  vertices.clear();
  faces.clear();
  for (const auto& o : world_->objects) {
    if (o.info.track_id != track_id || o.info.behaviour == Behaviour::Pedestrian) continue;
    std::map<std::array<float, 3>, int> index;
    auto vid = [&](const Vec3f& p_iso) {
      const Vec3f p = kittiFromIso(p_iso);
      const std::array<float, 3> key{p.x(), p.y(), p.z()};
      auto it = index.find(key);
      if (it != index.end()) return it->second;
      const int i = static_cast<int>(vertices.size());
      vertices.push_back(p);
      index.emplace(key, i);
      return i;
    };
    for (const Tri& t : o.mesh) faces.push_back({vid(t.a), vid(t.b), vid(t.c)});
  }
}

SequenceSummary Synthesizer::summary() const {
  SequenceSummary s;
  const World& w = *world_;
  s.frames = w.config.frames;
  s.parked = w.count_parked, s.driving = w.count_driving, s.stop_and_go = w.count_stop_and_go,
  s.pedestrians = w.count_pedestrians;
  s.loop_length_m = w.loop_length;
  s.distance_m = w.ego_profile.sAt(w.frameTime(w.config.frames - 1));
  s.laps = s.distance_m / w.loop_length;
  return s;
}

FrameRender Synthesizer::render(int frame) const {
  FrameRender out;
  render(frame, out);
  return out;
}

namespace {

// An object's pose and triangles (ISO object frame) at the frame's time.
struct ObjView {
  const Object* o;
  Eigen::Isometry3d T_sim_iso;
  std::vector<Tri> tris;
};

// Index range [first, second) of each object's triangles in the camera's view triangles (empty: culled).
using TriRanges = std::vector<std::pair<std::size_t, std::size_t>>;

// Objects' poses at time t.
std::vector<ObjView> poseObjects(const World& w, double t) {
  std::vector<ObjView> objs;
  objs.reserve(w.objects.size());
  for (const auto& o : w.objects) {
    const Pose2 p = w.objectPose(o, t);
    ObjView ov{&o, Eigen::Isometry3d::Identity(), {}};
    ov.T_sim_iso.linear() = Eigen::AngleAxisd(p.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    ov.T_sim_iso.translation() = Eigen::Vector3d(p.x, p.y, p.z);
    w.objectTris(o, t, ov.tris);
    objs.push_back(std::move(ov));
  }
  return objs;
}

// Camera: frustum-culls chunks and objects into camera-frame triangles (sc.vt) and rasterises their ids
// and 1/z into sc.cam; returns each object's triangle range.
TriRanges rasteriseCamera(const World& w, const std::vector<ObjView>& objs, const Eigen::Isometry3d& T_cam_sim,
                          const Eigen::Matrix3f& Rcs, const Vec3f& tcs, const Vec3f& sun_sim, Scratch& sc) {
  const SynthConfig& cfg = w.config;
  const int W = cfg.camera.width, H = cfg.camera.height;
  RasterTarget& cam = sc.cam;
  cam.fx = static_cast<float>(cfg.camera.fx), cam.fy = static_cast<float>(cfg.camera.fy);
  cam.cx = static_cast<float>(cfg.camera.cx), cam.cy = static_cast<float>(cfg.camera.cy);
  cam.reset(W, H);
  std::vector<ViewTri>& vt = sc.vt;
  vt.clear();
  float planes[5][4];
  const int np = frustumPlanes(static_cast<float>(W), static_cast<float>(H), cam.fx, cam.fy, cam.cx, cam.cy, planes);
  const float farDist = 600.f;
  const Vec3f sun_cam = Rcs * sun_sim;
  for (const auto& ch : w.chunks) {
    const Sphere s = chunkSphere(ch);
    if (!sphereVisible(s, Rcs, tcs, planes, np, farDist)) continue;
    appendTris(ch.tris, Rcs, tcs, 0, sun_cam, vt);
  }
  TriRanges objRange(objs.size(), {0, 0});
  for (std::size_t i = 0; i < objs.size(); ++i) {
    const Eigen::Isometry3d T = T_cam_sim * objs[i].T_sim_iso;
    const Eigen::Matrix3f R = T.linear().cast<float>();
    const Vec3f tt = T.translation().cast<float>();
    const Sphere s{Vec3f(0, 0, 1), 3.5f};
    if (!sphereVisible(s, R, tt, planes, np, farDist)) continue;
    objRange[i].first = vt.size();
    appendTris(objs[i].tris, R, tt, static_cast<std::uint16_t>(objs[i].o->info.track_id), sun_cam, vt);
    objRange[i].second = vt.size();
  }
  for (std::size_t i = 0; i < vt.size(); ++i)
    drawTriangle(vt[i].a, vt[i].b, vt[i].c, static_cast<std::int32_t>(i), cam);
  return objRange;
}

// Shade: each camera pixel once, into linear radiance (sc.lin), the instance mask and the depth.
void shadeCamera(const World& w, const Eigen::Matrix3f& Rcs, Scratch& sc, FrameRender& out) {
  const SynthConfig& cfg = w.config;
  const int W = cfg.camera.width, H = cfg.camera.height;
  const RasterTarget& cam = sc.cam;
  const std::vector<ViewTri>& vt = sc.vt;
  const Eigen::Matrix3f Rsc = Rcs.transpose();
  sc.lin.create(H, W, CV_32FC3);
  cv::Mat& lin = sc.lin;
  out.instance.create(H, W, CV_16UC1);
  out.depth.create(H, W, CV_32FC1);
  const Vec3f hazeColour(0.72f, 0.78f, 0.85f);
  for (int y = 0; y < H; ++y) {
    const float ry = (y - cam.cy) / cam.fy;
    auto* lrow = lin.ptr<cv::Vec3f>(y);
    auto* irow = out.instance.ptr<std::uint16_t>(y);
    auto* drow = out.depth.ptr<float>(y);
    for (int x = 0; x < W; ++x) {
      const std::size_t k = static_cast<std::size_t>(y) * W + x;
      const float rx = (x - cam.cx) / cam.fx;
      const std::int32_t id = cam.id[k];
      Vec3f c;
      if (id < 0) {
        c = shadeSky((Rsc * Vec3f(rx, ry, 1.f)).normalized());
        irow[x] = 0;
        drow[x] = 0;
      } else {
        const ViewTri& tr = vt[static_cast<std::size_t>(id)];
        const float z = 1.f / cam.invz[k];
        const Vec3f p(rx * z, ry * z, z);
        const float rn = std::sqrt(rx * rx + ry * ry + 1.f);
        const float cosv = std::max(0.12f, std::abs(tr.n.x() * rx + tr.n.y() * ry + tr.n.z()) / rn);
        ShadeInput in;
        in.material = tr.material;
        in.param = tr.param;
        in.u = tr.U.x() * p.x() + tr.U.y() * p.y() + tr.U.z() * p.z() + tr.U.w();
        in.v = tr.V.x() * p.x() + tr.V.y() * p.y() + tr.V.z() * p.z() + tr.V.w();
        in.footprint = z * rn / (cam.fx * cosv);
        c = shadeSurface(w, in) * tr.light;
        const float dist = z * rn;
        const float haze = dist / (dist + 700.f);
        c = c + (hazeColour - c) * haze;
        irow[x] = tr.instance;
        drow[x] = z;
      }
      lrow[x] = cv::Vec3f(c.z(), c.y(), c.x());  // BGR
    }
  }
}

// The horizontal pass of the separable blur (sc.lin into sc.tmp) with the half kernel kern[0..radius].
void blurRows(const float kern[8], int radius, int W, int H, Scratch& sc) {
  const cv::Mat& lin = sc.lin;
  sc.tmp.create(H, W, CV_32FC3);
  for (int y = 0; y < H; ++y) {
    const float* src = lin.ptr<float>(y);
    float* dst = sc.tmp.ptr<float>(y);
    if (radius == 1) {  // the usual case: a 3-tap kernel, interior without clamping
      const float k0 = kern[0], k1 = kern[1];
      for (int ch = 0; ch < 3; ++ch) {
        dst[ch] = k0 * src[ch] + k1 * (src[ch] + src[3 + ch]);
        dst[3 * (W - 1) + ch] = k0 * src[3 * (W - 1) + ch] + k1 * (src[3 * (W - 2) + ch] + src[3 * (W - 1) + ch]);
      }
      for (int i = 3; i < 3 * (W - 1); ++i) dst[i] = k0 * src[i] + k1 * (src[i - 3] + src[i + 3]);
      continue;
    }
    for (int x = 0; x < W; ++x)
      for (int ch = 0; ch < 3; ++ch) {
        float acc = kern[0] * src[3 * x + ch];
        for (int i = 1; i <= radius; ++i)
          acc += kern[i] * (src[3 * std::max(0, x - i) + ch] + src[3 * std::min(W - 1, x + i) + ch]);
        dst[3 * x + ch] = acc;
      }
  }
}

// Image effects: exposure, blur, noise; grey from the same radiance (sc.lin into out.colour and out.grey).
// Returns the frame's noise seed (the LiDAR's range noise draws from it too).
std::uint32_t applyImageEffects(const SynthConfig& cfg, int frame, Scratch& sc, FrameRender& out) {
  const int W = cfg.camera.width, H = cfg.camera.height;
  const double ph = static_cast<double>(mixSeed(cfg.seed, 6) % 1000) / 159.0;
  const float gain = static_cast<float>(
      1.0 + cfg.image.exposure_variation * (0.6 * std::sin(0.21 * frame + ph) + 0.4 * std::sin(0.77 * frame + 2 * ph)) +
      0.3 * cfg.image.exposure_variation *
          (hashf(static_cast<std::uint32_t>(cfg.seed), static_cast<std::uint32_t>(frame), 77) - 0.5f));
  // Separable blur (horizontal into tmp, vertical fused with gain, noise and quantisation).
  int radius = 0;
  float kern[8] = {1, 0, 0, 0, 0, 0, 0, 0};
  if (cfg.image.blur_sigma > 0) {
    const double sg = cfg.image.blur_sigma;
    radius = std::min(7, std::max(1, static_cast<int>(std::lround(2.0 * sg))));
    float sum = 0;
    for (int i = 0; i <= radius; ++i) kern[i] = static_cast<float>(std::exp(-0.5 * i * i / (sg * sg)));
    for (int i = 0; i <= radius; ++i) sum += (i ? 2.f : 1.f) * kern[i];
    for (int i = 0; i <= radius; ++i) kern[i] /= sum;
  }
  blurRows(kern, radius, W, H, sc);
  sc.vrow.resize(static_cast<std::size_t>(3) * W);
  const float sigma = static_cast<float>(cfg.image.noise_sigma);
  const std::uint32_t fseed = hash3(static_cast<std::uint32_t>(cfg.seed), static_cast<std::uint32_t>(cfg.seed >> 32),
                                    static_cast<std::uint32_t>(frame));
  const std::vector<float>& table = noiseTable();
  const std::size_t mask = table.size() - 1;
  if (cfg.camera.colour)
    out.colour.create(H, W, CV_8UC3);
  else
    out.colour.release();
  if (cfg.camera.grey)
    out.grey.create(H, W, CV_8UC1);
  else
    out.grey.release();
  const float scale = 255.f * gain;
  for (int y = 0; y < H; ++y) {
    const float* rows[15];
    for (int i = -radius; i <= radius; ++i) rows[i + radius] = sc.tmp.ptr<float>(std::clamp(y + i, 0, H - 1));
    // Each row reads the noise table from its own pseudo-random offset.
    std::size_t o = hash3(fseed, static_cast<std::uint32_t>(y), 5u);
    std::uint8_t* crow = cfg.camera.colour ? out.colour.ptr<std::uint8_t>(y) : nullptr;
    std::uint8_t* grow = cfg.camera.grey ? out.grey.ptr<std::uint8_t>(y) : nullptr;
    // Vertical pass of the blur into a row buffer (vectorises), then gain, noise and quantisation.
    float* vrow = sc.vrow.data();
    for (int i = 0; i < 3 * W; ++i) vrow[i] = kern[0] * rows[radius][i];
    for (int k = 1; k <= radius; ++k) {
      const float* a = rows[radius - k];
      const float* b = rows[radius + k];
      const float kk = kern[k];
      for (int i = 0; i < 3 * W; ++i) vrow[i] += kk * (a[i] + b[i]);
    }
    for (int x = 0; x < W; ++x) {
      const float c[3] = {vrow[3 * x] * scale, vrow[3 * x + 1] * scale, vrow[3 * x + 2] * scale};
      if (crow) {
        crow[3 * x] = toByte(c[0] + sigma * table[(o + 1) & mask]);
        crow[3 * x + 1] = toByte(c[1] + sigma * table[(o + 2) & mask]);
        crow[3 * x + 2] = toByte(c[2] + sigma * table[(o + 3) & mask]);
      }
      if (grow) grow[x] = toByte(0.114f * c[0] + 0.587f * c[1] + 0.299f * c[2] + sigma * table[o & mask]);
      o += 4;
    }
  }
  return fseed;
}

// Truncation: share of the projected box (label L's size, pose T_cam_obj) outside the image.
double boxTruncation(const SynthConfig& cfg, const ObjectLabel& L, const Eigen::Isometry3d& T_cam_obj) {
  const int W = cfg.camera.width, H = cfg.camera.height;
  double u0 = 1e18, v0 = 1e18, u1 = -1e18, v1 = -1e18;
  bool behind = false;
  for (int cnr = 0; cnr < 8; ++cnr) {
    const Eigen::Vector3d pk((cnr & 1 ? 0.5 : -0.5) * L.l, (cnr & 2 ? -L.h : 0.0), (cnr & 4 ? 0.5 : -0.5) * L.w);
    const Eigen::Vector3d pc = T_cam_obj * pk;
    if (pc.z() < 0.1) {
      behind = true;
      continue;
    }
    const double u = cfg.camera.fx * pc.x() / pc.z() + cfg.camera.cx,
                 v = cfg.camera.fy * pc.y() / pc.z() + cfg.camera.cy;
    u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
  }
  if (behind) return 1.0;
  const double area = std::max(1e-9, (u1 - u0) * (v1 - v0));
  const double cu0 = std::max(u0, 0.0), cu1 = std::min(u1, W - 1.0), cv0 = std::max(v0, 0.0),
               cv1 = std::min(v1, H - 1.0);
  const double inside = std::max(0.0, cu1 - cu0) * std::max(0.0, cv1 - cv0);
  return std::clamp(1.0 - inside / area, 0.0, 1.0);
}

// Labels: a KITTI label for each object with at least 10 visible pixels (its full silhouette re-stamped
// from its camera triangles gives the box and the occlusion level).
void labelObjects(const World& w, double t, const std::vector<ObjView>& objs, const TriRanges& objRange,
                  const Eigen::Isometry3d& T_cam_sim, Scratch& sc, FrameRender& out) {
  const SynthConfig& cfg = w.config;
  const int W = cfg.camera.width, H = cfg.camera.height;
  const RasterTarget& cam = sc.cam;
  const std::vector<ViewTri>& vt = sc.vt;
  std::vector<int>& visible = sc.visible;
  visible.assign(65536, 0);
  for (int y = 0; y < H; ++y) {
    const auto* row = out.instance.ptr<std::uint16_t>(y);
    for (int x = 0; x < W; ++x)
      if (row[x]) ++visible[row[x]];
  }
  RasterTarget stampTarget;  // geometry only, no buffers
  stampTarget.W = cam.W, stampTarget.H = cam.H, stampTarget.fx = cam.fx, stampTarget.fy = cam.fy;
  stampTarget.cx = cam.cx, stampTarget.cy = cam.cy, stampTarget.near = cam.near;
  std::vector<std::int32_t>& stamp = sc.stamp;
  stamp.assign(static_cast<std::size_t>(W) * H, -1);
  for (std::size_t i = 0; i < objs.size(); ++i) {
    const Object& o = *objs[i].o;
    const int tid = o.info.track_id;
    if (visible[tid] < 10 || objRange[i].second == objRange[i].first) continue;
    int full = 0, bx0 = W, by0 = H, bx1 = -1, by1 = -1;
    for (std::size_t k = objRange[i].first; k < objRange[i].second; ++k) {
      rasterizeTriangle(vt[k].a, vt[k].b, vt[k].c, stampTarget, [&](int y, int x0, int x1, float, float, float) {
        std::int32_t* row = stamp.data() + static_cast<std::size_t>(y) * W;
        for (int x = x0; x <= x1; ++x) {
          full += row[x] != tid;
          row[x] = tid;
        }
        bx0 = std::min(bx0, x0), bx1 = std::max(bx1, x1), by0 = std::min(by0, y), by1 = std::max(by1, y);
      });
    }
    if (full == 0) continue;
    ObjectLabel L;
    L.track_id = tid;
    L.type = o.info.type;
    L.visible_pixels = visible[tid];
    const double ratio = static_cast<double>(visible[tid]) / full;
    L.occluded = ratio >= 0.8 ? 0 : (ratio >= 0.4 ? 1 : 2);
    L.x1 = bx0, L.y1 = by0, L.x2 = bx1, L.y2 = by1;
    L.h = o.info.height, L.w = o.info.width, L.l = o.info.length;
    const Eigen::Isometry3d T_cam_obj = T_cam_sim * w.T_sim_obj(o, t);
    L.location = T_cam_obj.translation();
    const Eigen::Vector3d heading = T_cam_obj.linear().col(0);
    L.ry = std::atan2(-heading.z(), heading.x());
    L.alpha = L.ry - std::atan2(L.location.x(), L.location.z());
    while (L.alpha > M_PI) L.alpha -= 2 * M_PI;
    while (L.alpha < -M_PI) L.alpha += 2 * M_PI;
    L.truncated = boxTruncation(cfg, L, T_cam_obj);
    out.labels.push_back(L);
  }
}

// The LiDAR's four raster faces round the sensor: their geometry and the beams' elevation range.
struct LidarFaces {
  double up, down;  // elevation of the first and the last beam (radians)
  int cols;         // columns per revolution
  float f;          // the faces' horizontal focal length (px)
};

// Rasterises the LiDAR-frame triangles lt into the four faces (candidate triangles per pixel).
LidarFaces rasteriseLidarFaces(const SynthConfig& cfg, const std::vector<ViewTri>& lt, RasterTarget face[4]) {
  const double deg = M_PI / 180.0;
  const double up = cfg.lidar.fov_up_deg * deg, down = cfg.lidar.fov_down_deg * deg;
  const double margin = 0.6 * deg;
  const double c45 = std::cos(M_PI / 4);
  const double ymin = -std::tan(up + margin) / (up + margin > 0 ? c45 : 1.0);
  const double ymax = -std::tan(down - margin) / (down - margin < 0 ? c45 : 1.0);
  const int cols = static_cast<int>(std::lround(360.0 / cfg.lidar.horizontal_resolution_deg));
  const int faceW = std::max(64, static_cast<int>(std::ceil(cols / 4.0 * 1.15)));
  const float f = faceW / 2.f;
  for (int k = 0; k < 4; ++k) {
    RasterTarget& ft = face[k];
    ft.fx = f;
    ft.fy = 0.5f * f;  // beams are twice as far apart vertically as columns horizontally
    ft.cx = (faceW - 1) / 2.f;
    ft.cy = static_cast<float>(-ymin * ft.fy) + 1.f;
    ft.near = 0.05f;
    ft.reset(faceW, static_cast<int>(std::ceil((ymax - ymin) * ft.fy)) + 3);
    // Face k looks along azimuth k * 90 deg (0 forward, 90 left): z_F = p . dir, x_F = p . right.
    const double az = k * M_PI / 2;
    const Vec3f dir(static_cast<float>(-std::sin(az)), 0, static_cast<float>(std::cos(az)));
    const Vec3f right(static_cast<float>(std::cos(az)), 0, static_cast<float>(std::sin(az)));
    auto toFace = [&](const Vec3f& p) { return Vec3f(p.dot(right), p.y(), p.dot(dir)); };
    for (std::size_t i = 0; i < lt.size(); ++i) {
      const Vec3f a = toFace(lt[i].a), b = toFace(lt[i].b), c = toFace(lt[i].c);
      if (a.z() < 0 && b.z() < 0 && c.z() < 0) continue;
      drawTriangle(a, b, c, static_cast<std::int32_t>(i), ft);
    }
  }
  return {up, down, cols, f};
}

// Casts every beam of every column against the candidate triangles of the faces and appends the returns
// (x, y, z, intensity in the LiDAR frame) to out.lidar.
void castBeams(const SynthConfig& cfg, const std::vector<ViewTri>& lt, const RasterTarget face[4], const LidarFaces& lf,
               std::uint32_t fseed, FrameRender& out) {
  const double up = lf.up, down = lf.down;
  const int cols = lf.cols;
  const float f = lf.f;
  const float range = static_cast<float>(cfg.lidar.max_range);
  const int beams = cfg.lidar.beams;
  // Per-beam and per-column trigonometry, computed once per frame.
  std::vector<float> te(beams), ce(beams), se(beams);
  for (int bm = 0; bm < beams; ++bm) {
    const double e = beams == 1 ? up : up + (down - up) * bm / (beams - 1);
    te[bm] = static_cast<float>(std::tan(e)), ce[bm] = static_cast<float>(std::cos(e)),
    se[bm] = static_cast<float>(std::sin(e));
  }
  struct Col {
    float ca, sa, sx, inv_cos_a;
    int face;
  };
  std::vector<Col> colInfo(cols);
  for (int col = 0; col < cols; ++col) {
    const double alpha = 2 * M_PI * col / cols;  // 0 forward, counter-clockwise (left)
    const int kk = static_cast<int>(std::floor((alpha + M_PI / 4) / (M_PI / 2)));
    const double a = alpha - kk * M_PI / 2;
    colInfo[col] = {static_cast<float>(std::cos(alpha)), static_cast<float>(std::sin(alpha)),
                    static_cast<float>(-f * std::tan(a) + face[kk % 4].cx), static_cast<float>(1.0 / std::cos(a)),
                    kk % 4};
  }
  out.lidar.reserve(static_cast<std::size_t>(beams) * cols * 4);
  const float noise = static_cast<float>(cfg.lidar.range_noise);
  const Vec3f origin(0, 0, 0);
  const std::vector<float>& table = noiseTable();
  const std::size_t tmask = table.size() - 1;
  std::size_t to = hash3(fseed, 0xa5a5u, 9u);
  for (int bm = 0; bm < beams; ++bm) {
    for (int col = 0; col < cols; ++col) {
      const Col& ci = colInfo[col];
      const RasterTarget& ft = face[ci.face];
      const float sx = ci.sx;
      const float sy = ft.fy * (-te[bm] * ci.inv_cos_a) + ft.cy;
      const Vec3f dirL(-ce[bm] * ci.sa, -se[bm], ce[bm] * ci.ca);
      // Candidates: the 2 x 2 pixels round the ray, then a 4 x 4 ring if none of them is hit.
      float best = 1e30f;
      int bestId = -1;
      std::int32_t seen[16];
      int nseen = 0;
      const int bx = static_cast<int>(std::floor(sx)), by = static_cast<int>(std::floor(sy));
      for (int pass = 0; pass < 2 && bestId < 0; ++pass) {
        const int lo = pass == 0 ? 0 : -1, hi = pass == 0 ? 1 : 2;
        for (int dy = lo; dy <= hi; ++dy)
          for (int dx = lo; dx <= hi; ++dx) {
            if (pass == 1 && dx >= 0 && dx <= 1 && dy >= 0 && dy <= 1) continue;
            const int xx = bx + dx, yy = by + dy;
            if (xx < 0 || yy < 0 || xx >= ft.W || yy >= ft.H) continue;
            const std::int32_t id = ft.id[static_cast<std::size_t>(yy) * ft.W + xx];
            if (id < 0) continue;
            bool dup = false;
            for (int q = 0; q < nseen; ++q) dup = dup || seen[q] == id;
            if (dup || nseen >= 16) continue;
            seen[nseen++] = id;
            float dist;
            if (rayTriangle(origin, dirL, lt[static_cast<std::size_t>(id)], dist) && dist < best)
              best = dist, bestId = id;
          }
      }
      to += 1;
      if (bestId < 0 || best > range || best < 1.0f) continue;
      const ViewTri& tr = lt[static_cast<std::size_t>(bestId)];
      const float r = best + noise * table[to & tmask];
      const float cosi = std::abs(tr.n.dot(dirL));
      const float inten = std::clamp(lidarReflectance(tr.material) * (0.3f + 0.7f * cosi), 0.f, 1.f);
      out.lidar.push_back(r * ce[bm] * ci.ca);
      out.lidar.push_back(r * ce[bm] * ci.sa);
      out.lidar.push_back(r * se[bm]);
      out.lidar.push_back(inten);
    }
  }
}

// LiDAR: the scene within range in a camera-like frame at the sensor (sc.lt), rasterised into four faces,
// then one exact ray-triangle intersection per beam.
void scanLidar(const World& w, const std::vector<ObjView>& objs, const Eigen::Isometry3d& T_sim_cam,
               const Vec3f& sun_sim, std::uint32_t fseed, Scratch& sc, FrameRender& out) {
  const SynthConfig& cfg = w.config;
  const Eigen::Isometry3d T_sim_velo = T_sim_cam * w.T_cam_velo;
  Eigen::Isometry3d T_L_velo = Eigen::Isometry3d::Identity();
  T_L_velo.linear() = w.T_cam_velo.linear();  // camera-like axes at the LiDAR origin
  const Eigen::Isometry3d T_L_sim = T_L_velo * T_sim_velo.inverse();
  const Eigen::Matrix3f RL = T_L_sim.linear().cast<float>();
  const Vec3f tL = T_L_sim.translation().cast<float>();
  const float range = static_cast<float>(cfg.lidar.max_range);
  std::vector<ViewTri>& lt = sc.lt;
  lt.clear();
  const Vec3f sun_L = RL * sun_sim;
  for (const auto& ch : w.chunks) {
    const Sphere s = chunkSphere(ch);
    if ((RL * s.c + tL).norm() - s.r > range) continue;
    appendTris(ch.tris, RL, tL, 0, sun_L, lt);
  }
  for (const auto& ov : objs) {
    const Eigen::Isometry3d T = T_L_sim * ov.T_sim_iso;
    const Eigen::Matrix3f R = T.linear().cast<float>();
    const Vec3f tt = T.translation().cast<float>();
    if (tt.norm() - 3.5f > range) continue;
    appendTris(ov.tris, R, tt, static_cast<std::uint16_t>(ov.o->info.track_id), sun_L, lt);
  }
  const LidarFaces lf = rasteriseLidarFaces(cfg, lt, sc.face);
  castBeams(cfg, lt, sc.face, lf, fseed, out);
}

}  // namespace

void Synthesizer::render(int frame, FrameRender& out) const {
  const World& w = *world_;
  const SynthConfig& cfg = w.config;
  const double t = w.frameTime(frame);
  out.index = frame;
  out.labels.clear();
  out.lidar.clear();
  out.stamp = t;
  const Eigen::Isometry3d T_sim_cam = w.T_sim_cam(t);
  out.T_world_cam = w.T_sim_cam0.inverse() * T_sim_cam;
  const Eigen::Isometry3d T_cam_sim = T_sim_cam.inverse();
  const Eigen::Matrix3f Rcs = T_cam_sim.linear().cast<float>();
  const Vec3f tcs = T_cam_sim.translation().cast<float>();
  const double sunAz = static_cast<double>(mixSeed(cfg.seed, 5) % 6283) / 1000.0;
  const Vec3f sun_sim =
      Vec3f(static_cast<float>(std::cos(sunAz) * 0.55), static_cast<float>(std::sin(sunAz) * 0.55), 0.83f).normalized();

  const std::vector<ObjView> objs = poseObjects(w, t);
  Scratch& sc = scratch();
  const TriRanges objRange = rasteriseCamera(w, objs, T_cam_sim, Rcs, tcs, sun_sim, sc);
  shadeCamera(w, Rcs, sc, out);
  const std::uint32_t fseed = applyImageEffects(cfg, frame, sc, out);
  labelObjects(w, t, objs, objRange, T_cam_sim, sc, out);
  if (cfg.lidar.enabled) scanLidar(w, objs, T_sim_cam, sun_sim, fseed, sc, out);
}

}  // namespace beslam::sim
