#include "map_io/map_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "features/checksum.hpp"
#include "features/feature_set.hpp"
#include "map/frame.hpp"
#include "map/keyframe.hpp"
#include "map/map.hpp"
#include "map/map_point.hpp"

namespace beslam::orb {
namespace {

constexpr char kMagic[8] = {'B', 'E', 'S', 'L', 'A', 'M', 'A', 'P'};
constexpr size_t kHeaderBytes = 8 + 4 + 8, kTrailerBytes = 8;
// Sanity bounds on counts (a corrupt count must not allocate gigabytes before the length check fails).
constexpr uint32_t kMaxKeyFrames = 10'000'000, kMaxKeypoints = 1'000'000, kMaxPoints = 100'000'000;
constexpr uint32_t kMaxLinks = 10'000'000, kMaxLandmarks = 1'000'000, kMaxSurfacePoints = 10'000'000;
constexpr uint32_t kMaxText = 4096;

// ------------------------------------------------------------------ encoding

class Writer {
 public:
  void u8(uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u16(uint16_t v) { le(v, 2); }
  void u32(uint32_t v) { le(v, 4); }
  void u64(uint64_t v) { le(v, 8); }
  void i32(int32_t v) { le(static_cast<uint32_t>(v), 4); }
  void i64(int64_t v) { le(static_cast<uint64_t>(v), 8); }
  void f32(float v) {
    uint32_t b;
    std::memcpy(&b, &v, 4);
    u32(b);
  }
  void f64(double v) {
    uint64_t b;
    std::memcpy(&b, &v, 8);
    u64(b);
  }
  void bytes(const void* p, size_t n) { out_.append(static_cast<const char*>(p), n); }
  void text(const std::string& s) {
    u32(static_cast<uint32_t>(s.size()));
    bytes(s.data(), s.size());
  }
  void pose(const Eigen::Isometry3d& T) {  // rotation row by row, then translation
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) f64(T.linear()(r, c));
    for (int r = 0; r < 3; ++r) f64(T.translation()(r));
  }
  void vec3(const Eigen::Vector3d& v) {
    for (int r = 0; r < 3; ++r) f64(v(r));
  }
  std::string& buffer() { return out_; }

 private:
  void le(uint64_t v, int n) {
    for (int i = 0; i < n; ++i) out_.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  }
  std::string out_;
};

struct Corrupt : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Reader {
 public:
  Reader(const char* data, size_t size) : p_(data), end_(data + size), begin_(data) {}
  uint8_t u8() { return static_cast<uint8_t>(le(1)); }
  uint16_t u16() { return static_cast<uint16_t>(le(2)); }
  uint32_t u32() { return static_cast<uint32_t>(le(4)); }
  uint64_t u64() { return le(8); }
  int32_t i32() { return static_cast<int32_t>(u32()); }
  int64_t i64() { return static_cast<int64_t>(u64()); }
  float f32() {
    const uint32_t b = u32();
    float v;
    std::memcpy(&v, &b, 4);
    return v;
  }
  double f64() {
    const uint64_t b = u64();
    double v;
    std::memcpy(&v, &b, 8);
    return v;
  }
  double finite(const char* what) {
    const double v = f64();
    if (!std::isfinite(v)) fail(std::string("non-finite ") + what);
    return v;
  }
  void bytes(void* dst, size_t n) {
    need(n);
    std::memcpy(dst, p_, n);
    p_ += n;
  }
  std::string text() {
    const uint32_t n = count(kMaxText, 1, "text length");
    std::string s(p_, n);
    p_ += n;
    return s;
  }
  Eigen::Isometry3d pose(const char* what) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) T.linear()(r, c) = finite(what);
    for (int r = 0; r < 3; ++r) T.translation()(r) = finite(what);
    const Eigen::Matrix3d R = T.linear();
    if (!(R.transpose() * R).isApprox(Eigen::Matrix3d::Identity(), 1e-6) || R.determinant() < 0)
      fail(std::string(what) + " is not a rigid transform");
    return T;
  }
  Eigen::Vector3d vec3(const char* what) {
    Eigen::Vector3d v;
    for (int r = 0; r < 3; ++r) v(r) = finite(what);
    return v;
  }
  // A count of records of at least min_bytes each: within `max` and within what is left of the payload.
  uint32_t count(uint32_t max, size_t min_bytes, const char* what) {
    const uint32_t n = u32();
    if (n > max || static_cast<uint64_t>(n) * min_bytes > static_cast<uint64_t>(end_ - p_))
      fail(std::string(what) + " " + std::to_string(n) + " is out of bounds");
    return n;
  }
  bool done() const { return p_ == end_; }
  [[noreturn]] void fail(const std::string& what) const {
    throw Corrupt(what + " (payload byte " + std::to_string(p_ - begin_) + ")");
  }

 private:
  void need(size_t n) {
    if (static_cast<size_t>(end_ - p_) < n) fail("unexpected end of data");
  }
  uint64_t le(int n) {
    need(static_cast<size_t>(n));
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= static_cast<uint64_t>(static_cast<uint8_t>(p_[i])) << (8 * i);
    p_ += n;
    return v;
  }
  const char* p_;
  const char* end_;
  const char* begin_;
};

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw std::runtime_error("map file '" + path + "': " + problem);
}

std::string describe(const Camera& c) {
  std::ostringstream s;
  s.precision(10);
  s << c.width << "x" << c.height << " fx " << c.fx << " fy " << c.fy << " cx " << c.cx << " cy " << c.cy;
  return s.str();
}

bool sameValue(double a, double b) {
  return std::abs(a - b) <= 1e-9 * std::max(1.0, std::max(std::abs(a), std::abs(b)));
}

bool sameCamera(const Camera& a, const Camera& b) {
  return a.width == b.width && a.height == b.height && sameValue(a.fx, b.fx) && sameValue(a.fy, b.fy) &&
         sameValue(a.cx, b.cx) && sameValue(a.cy, b.cy);
}

// The nearest live keyframe up a (culled) keyframe's parent chain.
const KeyFrame* liveAncestor(const KeyFrame* kf) {
  while (kf && kf->bad) kf = kf->parent;
  return kf;
}

// Writes the pieces, one after the other, to a temporary file next to `path`, flushes it to disk and
// renames it over `path`.
void writeAtomically(const std::string& path, const std::vector<const std::string*>& pieces) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  auto failed = [&](const std::string& what, int err) {
    ::unlink(tmp.c_str());
    fail(path, what + ": " + std::strerror(err) + " (an existing file is left as it was)");
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int err = errno;
    fail(path, "cannot create the temporary file '" + tmp + "': " + std::strerror(err) +
                   " (an existing file is left as it was)");
  }
  for (const std::string* bytes : pieces) {
    size_t done = 0;
    while (done < bytes->size()) {
      const ssize_t n = ::write(fd, bytes->data() + done, bytes->size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        const int err = n < 0 ? errno : EIO;
        ::close(fd);
        failed("cannot write", err);
      }
      done += static_cast<size_t>(n);
    }
  }
  if (::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    failed("cannot flush to disk", err);
  }
  if (::close(fd) != 0) failed("cannot close", errno);
  if (::rename(tmp.c_str(), path.c_str()) != 0) failed("cannot rename the temporary file over it", errno);
}

// ------------------------------------------------------------------ parsed form (checked before the map is touched)

struct KeyFrameRecord {
  int64_t id = 0, frame_index = 0, parent = -1;
  double timestamp = 0;
  Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  std::shared_ptr<FeatureSet> features;
  std::vector<std::pair<uint32_t, int64_t>> points;  // keypoint index, map point id
  std::vector<std::pair<int64_t, int32_t>> links;    // covisible keyframe id, weight
  std::vector<int64_t> loop_edges;                   // keyframe ids (version 3 on)
};

struct PointRecord {
  int64_t id = 0, reference = -1, first_keyframe = -1;
  Eigen::Vector3d position, normal;
  float min_distance = 0, max_distance = 0;
  Descriptor descriptor{};
  int32_t visible = 0, found = 0, object_id = -1;
  bool trusted = false;
  uint8_t grey = 0, r = 0, g = 0, b = 0;
  std::vector<std::pair<int64_t, uint32_t>> observations;  // keyframe id, keypoint index
};

}  // namespace

void saveMapFile(const std::string& path, const Map& map, const MapFileInfo& info,
                 const std::vector<ObjectLandmark>& landmarks) {
  Writer w;
  w.i32(info.camera.width);
  w.i32(info.camera.height);
  w.f64(info.camera.fx);
  w.f64(info.camera.fy);
  w.f64(info.camera.cx);
  w.f64(info.camera.cy);
  w.i32(info.levels);
  w.f64(info.scale_factor);
  w.text(info.vocabulary);
  w.u8(info.metric ? 1 : 0);
  w.i64(map.origin() ? map.origin()->id : -1);

  w.u32(static_cast<uint32_t>(map.keyframes().size()));
  for (const KeyFrame* kf : map.keyframes()) {
    const FeatureSet& f = *kf->features;
    w.i64(kf->id);
    w.i64(kf->frame_index);
    w.f64(kf->timestamp);
    w.pose(kf->T_cw);
    const KeyFrame* parent = liveAncestor(kf->parent);
    w.i64(parent ? parent->id : -1);
    w.u32(static_cast<uint32_t>(f.size()));
    for (size_t i = 0; i < f.size(); ++i) {
      const cv::KeyPoint& k = f.keypoints[i];
      w.f32(k.pt.x);
      w.f32(k.pt.y);
      w.f32(k.size);
      w.f32(k.angle);
      w.f32(k.response);
      w.u8(static_cast<uint8_t>(k.octave));
      w.u16(f.labels[i]);
      w.bytes(&f.colours[i][0], 3);
    }
    for (size_t i = 0; i < f.size(); ++i) w.bytes(f.descriptor(i), 32);
    w.u8(f.object_range.size() == f.size() && !f.object_range.empty() ? 1 : 0);
    if (f.object_range.size() == f.size() && !f.object_range.empty())
      for (float r : f.object_range) w.f32(r);
    std::vector<std::pair<uint32_t, int64_t>> points;
    for (size_t i = 0; i < kf->points.size(); ++i)
      if (kf->points[i] && !kf->points[i]->bad) points.emplace_back(static_cast<uint32_t>(i), kf->points[i]->id);
    w.u32(static_cast<uint32_t>(points.size()));
    for (const auto& [i, id] : points) {
      w.u32(i);
      w.i64(id);
    }
    std::vector<std::pair<int64_t, int32_t>> links;
    for (const auto& [other, weight] : kf->connections())
      if (!other->bad) links.emplace_back(other->id, weight);
    w.u32(static_cast<uint32_t>(links.size()));
    for (const auto& [id, weight] : links) {
      w.i64(id);
      w.i32(weight);
    }
    std::vector<int64_t> loop_edges;  // the keyframes it closed a loop with (essential graph, never culled)
    for (const KeyFrame* other : kf->loop_edges)
      if (!other->bad) loop_edges.push_back(other->id);
    w.u32(static_cast<uint32_t>(loop_edges.size()));
    for (int64_t id : loop_edges) w.i64(id);
  }

  w.u32(static_cast<uint32_t>(map.points().size()));
  for (const MapPoint* mp : map.points()) {
    std::vector<std::pair<int64_t, uint32_t>> obs;
    for (const auto& [kf, idx] : mp->observations)
      if (!kf->bad) obs.emplace_back(kf->id, static_cast<uint32_t>(idx));
    const KeyFrame* ref = liveAncestor(mp->reference);
    w.i64(mp->id);
    w.i64(ref ? ref->id : (obs.empty() ? -1 : obs.front().first));
    w.i64(mp->first_keyframe_id);
    w.vec3(mp->position);
    w.vec3(mp->normal);
    w.f32(mp->min_distance);
    w.f32(mp->max_distance);
    w.bytes(mp->descriptor.data(), 32);
    w.i32(mp->visible);
    w.i32(mp->found);
    w.u8(mp->trusted ? 1 : 0);
    w.i32(mp->object_id);
    w.u8(mp->grey);
    w.u8(mp->r);
    w.u8(mp->g);
    w.u8(mp->b);
    w.u32(static_cast<uint32_t>(obs.size()));
    for (const auto& [id, idx] : obs) {
      w.i64(id);
      w.u32(idx);
    }
  }

  w.u32(static_cast<uint32_t>(landmarks.size()));
  for (const ObjectLandmark& l : landmarks) {
    w.i64(l.id);
    w.f64(l.confidence);
    w.pose(l.T_world_object);
    w.vec3(l.dimensions);
    w.u32(static_cast<uint32_t>(l.points_object.size()));
    for (const Eigen::Vector3d& p : l.points_object) w.vec3(p);
  }

  const std::string& payload = w.buffer();
  Writer header, trailer;  // written around the payload, which is not copied
  header.bytes(kMagic, sizeof(kMagic));
  header.u32(kMapFileVersion);
  header.u64(payload.size());
  trailer.u64(fnv1a(payload.data(), payload.size()));
  writeAtomically(path, {&header.buffer(), &payload, &trailer.buffer()});
}

namespace {

// ------------------------------------------------------------------ loading, stage by stage

struct Payload {
  uint32_t version = 0;
  const char* data = nullptr;
  uint64_t size = 0;
};

// The payload between the header (magic, version, payload size) and the trailer (its checksum), all checked.
Payload checkEnvelope(const std::string& path, const std::string& data) {
  if (data.size() < sizeof(kMagic) || std::memcmp(data.data(), kMagic, sizeof(kMagic)) != 0)
    fail(path, "not a BE-SLAM map file (no BESLAMAP header)");
  if (data.size() < kHeaderBytes)
    fail(path, "truncated: " + std::to_string(data.size()) + " bytes, no complete header");
  Reader header(data.data() + sizeof(kMagic), kHeaderBytes - sizeof(kMagic));
  Payload p;
  p.version = header.u32();
  if (p.version < 1 || p.version > kMapFileVersion)
    fail(path, "format version " + std::to_string(p.version) + "; this build reads versions 1 to " +
                   std::to_string(kMapFileVersion));
  p.size = header.u64();
  const uint64_t expected_size = kHeaderBytes + p.size + kTrailerBytes;
  if (p.size > data.size() || data.size() != expected_size)
    fail(path, std::string(data.size() < expected_size ? "truncated" : "corrupt") + ": " + std::to_string(data.size()) +
                   " bytes where the header says " + std::to_string(expected_size));
  p.data = data.data() + kHeaderBytes;
  Reader trailer(p.data + p.size, kTrailerBytes);
  if (trailer.u64() != fnv1a(p.data, p.size)) fail(path, "corrupt: checksum mismatch");
  return p;
}

// The payload's first record: what the map was made with, and its origin keyframe's id.
MapFileInfo readInfo(Reader& r, int64_t& origin_id) {
  MapFileInfo info;
  info.camera.width = r.i32();
  info.camera.height = r.i32();
  info.camera.fx = r.finite("camera");
  info.camera.fy = r.finite("camera");
  info.camera.cx = r.finite("camera");
  info.camera.cy = r.finite("camera");
  info.levels = r.i32();
  info.scale_factor = r.finite("scale factor");
  info.vocabulary = r.text();
  info.metric = r.u8() != 0;
  origin_id = r.i64();
  return info;
}

// Checks that cannot wait for the whole file: the keypoints' octaves need this build's pyramid.
void checkMadeLikeThisRun(const std::string& path, const MapFileInfo& info, const MapFileInfo& expected) {
  if (!sameCamera(info.camera, expected.camera))
    fail(path, "made with camera " + describe(info.camera) + "; this run's camera is " + describe(expected.camera));
  if (info.levels != expected.levels || !sameValue(info.scale_factor, expected.scale_factor))
    fail(path, "made with " + std::to_string(info.levels) + " pyramid levels x " + std::to_string(info.scale_factor) +
                   "; this run uses " + std::to_string(expected.levels) + " x " +
                   std::to_string(expected.scale_factor) + " (options levels, scale_factor)");
  if (!info.vocabulary.empty() && !expected.vocabulary.empty() && info.vocabulary != expected.vocabulary)
    fail(path, "made with vocabulary '" + info.vocabulary + "'; this run uses '" + expected.vocabulary + "'");
}

// A keyframe's features: keypoints (checked against the image and the pyramid), descriptors, object ranges.
std::shared_ptr<FeatureSet> readFeatures(Reader& r, const MapFileInfo& info) {
  constexpr size_t kKeypointBytes = 5 * 4 + 1 + 2 + 3 + 32;
  const uint32_t n = r.count(kMaxKeypoints, kKeypointBytes, "keypoint count");
  auto f = std::make_shared<FeatureSet>();
  f->width = info.camera.width;
  f->height = info.camera.height;
  f->keypoints.resize(n);
  f->labels.resize(n);
  f->colours.resize(n);
  for (uint32_t i = 0; i < n; ++i) {
    cv::KeyPoint& kp = f->keypoints[i];
    kp.pt.x = r.f32();
    kp.pt.y = r.f32();
    kp.size = r.f32();
    kp.angle = r.f32();
    kp.response = r.f32();
    kp.octave = r.u8();
    if (!std::isfinite(kp.pt.x) || !std::isfinite(kp.pt.y) || !std::isfinite(kp.angle)) r.fail("non-finite keypoint");
    // Keypoints are found in the image; one outside it (found by fuzzing: -2.8e24) would overflow the
    // feature grid's cell index.
    if (!(kp.pt.x >= 0 && kp.pt.x < info.camera.width && kp.pt.y >= 0 && kp.pt.y < info.camera.height))
      r.fail("keypoint at (" + std::to_string(kp.pt.x) + ", " + std::to_string(kp.pt.y) + ") outside the " +
             std::to_string(info.camera.width) + "x" + std::to_string(info.camera.height) + " image");
    if (kp.octave >= info.levels) r.fail("keypoint octave " + std::to_string(kp.octave) + " out of range");
    f->labels[i] = r.u16();
    r.bytes(&f->colours[i][0], 3);
  }
  f->descriptors = cv::Mat(static_cast<int>(n), 32, CV_8U);
  if (n > 0) r.bytes(f->descriptors.data, static_cast<size_t>(n) * 32);
  if (r.u8() != 0) {
    f->object_range.resize(n);
    for (float& v : f->object_range) v = r.f32();
  }
  f->buildGrid();
  return f;
}

void readKeyFrame(Reader& r, const MapFileInfo& info, uint32_t version, KeyFrameRecord& k) {
  k.id = r.i64();
  k.frame_index = r.i64();
  k.timestamp = r.finite("timestamp");
  k.T_cw = r.pose("keyframe pose");
  k.parent = r.i64();
  k.features = readFeatures(r, info);
  const uint32_t n = static_cast<uint32_t>(k.features->size());
  const uint32_t n_points = r.count(n, 12, "keyframe point count");
  k.points.resize(n_points);
  for (auto& [idx, id] : k.points) {
    idx = r.u32();
    id = r.i64();
    if (idx >= n) r.fail("keyframe point at keypoint " + std::to_string(idx) + " of " + std::to_string(n));
  }
  const uint32_t n_links = r.count(kMaxLinks, 12, "covisibility link count");
  k.links.resize(n_links);
  for (auto& [id, weight] : k.links) {
    id = r.i64();
    weight = r.i32();
  }
  if (version >= 3) {  // version 2 had no loop edges
    k.loop_edges.resize(r.count(kMaxLinks, 8, "loop edge count"));
    for (int64_t& id : k.loop_edges) id = r.i64();
  }
}

void readPoint(Reader& r, uint32_t n_kfs, PointRecord& p) {
  p.id = r.i64();
  p.reference = r.i64();
  p.first_keyframe = r.i64();
  p.position = r.vec3("map point position");
  p.normal = r.vec3("map point normal");
  p.min_distance = r.f32();
  p.max_distance = r.f32();
  r.bytes(p.descriptor.data(), 32);
  p.visible = r.i32();
  p.found = r.i32();
  p.trusted = r.u8() != 0;
  p.object_id = r.i32();
  p.grey = r.u8();
  p.r = r.u8();
  p.g = r.u8();
  p.b = r.u8();
  const uint32_t n_obs = r.count(n_kfs, 12, "observation count");
  p.observations.resize(n_obs);
  for (auto& [id, idx] : p.observations) {
    id = r.i64();
    idx = r.u32();
  }
}

void readObject(Reader& r, uint32_t version, ObjectLandmark& o) {
  o.id = r.i64();
  o.confidence = version >= 2 ? r.finite("object confidence") : 1.0;  // version 1 had none
  o.T_world_object = r.pose("object pose");
  o.dimensions = r.vec3("object size");
  const uint32_t n = r.count(kMaxSurfacePoints, 24, "object surface point count");
  o.points_object.resize(n);
  for (Eigen::Vector3d& q : o.points_object) q = r.vec3("object surface point");
}

// Every id must resolve, every observation point at a keypoint that exists.
void checkReferences(const Reader& r, const std::vector<KeyFrameRecord>& kfs, const std::vector<PointRecord>& points,
                     int64_t origin_id) {
  std::unordered_map<int64_t, const KeyFrameRecord*> kf_by_id;
  std::unordered_map<int64_t, const PointRecord*> point_by_id;
  for (const KeyFrameRecord& k : kfs)
    if (!kf_by_id.emplace(k.id, &k).second || k.id < 0) r.fail("keyframe id " + std::to_string(k.id) + " repeated");
  for (const PointRecord& p : points)
    if (!point_by_id.emplace(p.id, &p).second || p.id < 0) r.fail("map point id " + std::to_string(p.id) + " repeated");
  if (!kfs.empty() && !kf_by_id.count(origin_id)) r.fail("origin keyframe " + std::to_string(origin_id) + " missing");
  for (const KeyFrameRecord& k : kfs) {
    if (k.parent >= 0 && !kf_by_id.count(k.parent))
      r.fail("keyframe " + std::to_string(k.id) + ": parent " + std::to_string(k.parent) + " missing");
    for (const auto& [idx, id] : k.points)
      if (!point_by_id.count(id))
        r.fail("keyframe " + std::to_string(k.id) + ": map point " + std::to_string(id) + " missing");
    for (const auto& [id, weight] : k.links)
      if (!kf_by_id.count(id) || id == k.id)
        r.fail("keyframe " + std::to_string(k.id) + ": covisible keyframe " + std::to_string(id) + " missing");
    for (int64_t id : k.loop_edges)
      if (!kf_by_id.count(id) || id == k.id)
        r.fail("keyframe " + std::to_string(k.id) + ": loop edge to keyframe " + std::to_string(id) + " missing");
  }
  for (const PointRecord& p : points) {
    if (!kf_by_id.count(p.reference))
      r.fail("map point " + std::to_string(p.id) + ": reference keyframe " + std::to_string(p.reference) + " missing");
    for (const auto& [id, idx] : p.observations) {
      auto it = kf_by_id.find(id);
      if (it == kf_by_id.end() || idx >= it->second->features->size())
        r.fail("map point " + std::to_string(p.id) + ": observation in keyframe " + std::to_string(id) +
               " at keypoint " + std::to_string(idx) + " does not exist");
    }
  }
}

// The parsed file, whole and checked.
struct MapRecords {
  MapFileInfo info;
  int64_t origin_id = -1;
  std::vector<KeyFrameRecord> kfs;
  std::vector<PointRecord> points;
  std::vector<ObjectLandmark> objects;
};

// Parses and checks the payload; a problem in it throws Corrupt.
void readPayload(const std::string& path, const Payload& payload, const MapFileInfo& expected, MapRecords& m) {
  Reader r(payload.data, payload.size);
  m.info = readInfo(r, m.origin_id);
  checkMadeLikeThisRun(path, m.info, expected);

  constexpr size_t kKeyFrameMinBytes = 8 * 3 + 8 * 13 + 4 * 3 + 1;
  const uint32_t n_kfs = r.count(kMaxKeyFrames, kKeyFrameMinBytes, "keyframe count");
  m.kfs.resize(n_kfs);
  for (KeyFrameRecord& k : m.kfs) readKeyFrame(r, m.info, payload.version, k);

  constexpr size_t kPointMinBytes = 8 * 3 + 8 * 6 + 4 * 2 + 32 + 4 * 2 + 1 + 4 + 4 + 4;
  const uint32_t n_points = r.count(kMaxPoints, kPointMinBytes, "map point count");
  m.points.resize(n_points);
  for (PointRecord& p : m.points) readPoint(r, n_kfs, p);

  const uint32_t n_objects =
      r.count(kMaxLandmarks, 8 + (payload.version >= 2 ? 8 : 0) + 8 * 15 + 4, "object landmark count");
  m.objects.resize(n_objects);
  for (ObjectLandmark& o : m.objects) readObject(r, payload.version, o);
  if (!r.done()) r.fail("data after the last record");

  checkReferences(r, m.kfs, m.points, m.origin_id);
}

// Builds the map from checked records (nothing can fail here).
void restoreMap(const MapRecords& m, const Camera& camera, const ScalePyramid& pyramid, Map& map) {
  std::unordered_map<int64_t, KeyFrame*> kf_ptr;
  std::unordered_map<int64_t, MapPoint*> point_ptr;
  for (const KeyFrameRecord& k : m.kfs) {
    Frame frame(k.frame_index, k.timestamp, k.features);
    frame.T_cw = k.T_cw;
    kf_ptr[k.id] = map.restoreKeyFrame(k.id, frame, camera, pyramid);
  }
  if (!m.kfs.empty()) map.setOrigin(kf_ptr.at(m.origin_id));
  for (const PointRecord& p : m.points) {
    MapPoint* mp = map.restoreMapPoint(p.id, p.position, kf_ptr.at(p.reference), p.first_keyframe);
    point_ptr[p.id] = mp;
    mp->normal = p.normal;
    mp->min_distance = p.min_distance;
    mp->max_distance = p.max_distance;
    mp->descriptor = p.descriptor;
    mp->visible = p.visible;
    mp->found = p.found;
    mp->trusted = p.trusted;
    mp->object_id = p.object_id;
    mp->grey = p.grey;
    mp->r = p.r;
    mp->g = p.g;
    mp->b = p.b;
    for (const auto& [id, idx] : p.observations) mp->addObservation(kf_ptr.at(id), idx);
  }
  for (const KeyFrameRecord& k : m.kfs) {
    KeyFrame* kf = kf_ptr.at(k.id);
    for (const auto& [idx, id] : k.points) kf->addPoint(point_ptr.at(id), idx);
    std::map<KeyFrame*, int, IdLess<KeyFrame>> weights;
    for (const auto& [id, weight] : k.links) weights[kf_ptr.at(id)] = weight;
    kf->restoreLinks(k.parent >= 0 ? kf_ptr.at(k.parent) : nullptr, weights);
    for (int64_t id : k.loop_edges) kf->loop_edges.insert(kf_ptr.at(id));
  }
}

}  // namespace

MapFileInfo loadMapFile(const std::string& path, const MapFileInfo& expected, const ScalePyramid& pyramid, Map& map,
                        std::vector<ObjectLandmark>& landmarks) {
  if (!map.keyframes().empty() || !map.points().empty()) fail(path, "cannot load into a map that is not empty");
  std::string data;
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
    std::ostringstream buffer;
    buffer << in.rdbuf();
    if (in.bad()) fail(path, "cannot read");
    data = buffer.str();
  }
  const Payload payload = checkEnvelope(path, data);
  MapRecords records;
  try {
    readPayload(path, payload, expected, records);
  } catch (const Corrupt& e) {
    fail(path, std::string("corrupt: ") + e.what());
  }
  restoreMap(records, expected.camera, pyramid, map);
  landmarks = std::move(records.objects);
  return records.info;
}

}  // namespace beslam::orb
