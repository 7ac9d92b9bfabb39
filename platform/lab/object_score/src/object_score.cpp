#include "beslam/object_score/object_score.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/common/run_folder.hpp"
#include "beslam/formats/labels.hpp"
#include "beslam/formats/ply.hpp"
#include "beslam/formats/trajectory.hpp"
#include "beslam/sdk/cli_args.hpp"

namespace fs = std::filesystem;

namespace beslam::object_score {

namespace {

using Mesh = formats::TriangleMesh;

// True when a ray from `origin` along `dir` hits a face of the mesh (Moller-Trumbore, t > 1e-5).
bool rayHits(const Mesh& mesh, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) {
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d& a = mesh.vertices[f[0]];
    const Eigen::Vector3d e1 = mesh.vertices[f[1]] - a, e2 = mesh.vertices[f[2]] - a;
    const Eigen::Vector3d h = dir.cross(e2);
    const double det = e1.dot(h);
    if (std::abs(det) < 1e-12) continue;
    const Eigen::Vector3d s = origin - a;
    const double u = s.dot(h) / det;
    if (u < 0 || u > 1) continue;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = dir.dot(q) / det;
    if (v < 0 || u + v > 1) continue;
    if (e2.dot(q) / det > 1e-5) return true;
  }
  return false;
}

// A point on the mesh is on its exterior when a ray in one of 14 directions (axes and diagonals) leaves
// without hitting the mesh; faces buried in another part (a generated car's wheel rims inside its body)
// fail every direction. Such faces are not what a sensor or a reconstruction can see.
bool onExterior(const Mesh& mesh, const Eigen::Vector3d& p) {
  static const std::vector<Eigen::Vector3d> kDirections = [] {
    std::vector<Eigen::Vector3d> d;
    for (int a = 0; a < 3; ++a)
      for (double sign : {-1.0, 1.0}) d.push_back(sign * Eigen::Vector3d::Unit(a));
    for (int k = 0; k < 8; ++k)
      d.push_back(Eigen::Vector3d(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1).normalized());
    return d;
  }();
  for (const Eigen::Vector3d& d : kDirections)
    if (!rayHits(mesh, p + 1e-4 * d, d)) return true;
  return false;
}

// Area-weighted samples on a mesh's surface, transformed by T (seeded: the same mesh gives the same
// samples); with exterior_only, samples on buried faces are drawn again (at most 20 n draws).
std::vector<Eigen::Vector3d> surfaceSamples(const Mesh& mesh, const Eigen::Isometry3d& T, int n,
                                            bool exterior_only = false) {
  const formats::SurfaceSampler sampler(mesh);
  std::vector<Eigen::Vector3d> out;
  if (sampler.totalArea() <= 0) return out;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  for (int draw = 0; static_cast<int>(out.size()) < n && draw < 20 * n; ++draw) {
    const size_t k = sampler.face(u(rng) * sampler.totalArea());
    const double a = u(rng), b = u(rng);
    const Eigen::Vector3d p = sampler.point(k, a, b);
    if (exterior_only && !onExterior(mesh, p)) continue;
    out.push_back(T * p);
  }
  return out;
}

double meanNearest(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to) {
  double sum = 0;
  for (const auto& p : from) {
    double best = 1e300;
    for (const auto& q : to) best = std::min(best, (p - q).squaredNorm());
    sum += std::sqrt(best);
  }
  return sum / double(from.size());
}

// Symmetric mean Chamfer distance between two point sets (metres).
double chamfer(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  if (a.empty() || b.empty()) return -1;
  return 0.5 * (meanNearest(a, b) + meanNearest(b, a));
}

// The landmark frame (x fwd, y left, z up, origin at the centre) in a KITTI object frame (x fwd, y down,
// z left, origin at the bottom centre) of a box of height h.
Eigen::Isometry3d kittiObjectFromLandmark(double h) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << 1, 0, 0,  //
      0, 0, -1,           //
      0, 1, 0;
  T.translation() = Eigen::Vector3d(0, -h / 2, 0);
  return T;
}

struct TruthObject {
  int32_t track_id = -1;
  std::string type, behaviour;
  double length = 0, width = 0, height = 0;
  bool parked = true;                                 // standing in every frame
  std::map<int64_t, Eigen::Isometry3d> T_world_kobj;  // per frame
};

Eigen::Isometry3d rowPose(std::istringstream& s) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) s >> T.matrix()(r, c);
  return T;
}

std::map<int32_t, TruthObject> readTruthObjects(const std::string& seq,
                                                const std::map<std::pair<int64_t, int64_t>, bool>& motion) {
  std::map<int32_t, TruthObject> objects;
  const std::string info_path = seq + "/objects/objects.txt";
  std::ifstream info(info_path);
  if (!info) throw Error(info_path + ": cannot open (is the run's dataset a beslam synth sequence?)");
  std::string line;
  int line_no = 0;
  while (std::getline(info, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    TruthObject o;
    std::string shape;
    if (!(s >> o.track_id >> o.type >> shape >> o.behaviour >> o.length >> o.width >> o.height))
      throw Error(info_path + ":" + std::to_string(line_no) + ": expected track_id type shape behaviour l w h");
    objects[o.track_id] = o;
  }
  const std::string poses_path = seq + "/objects/poses.txt";
  std::ifstream poses(poses_path);
  if (!poses) throw Error(poses_path + ": cannot open");
  line_no = 0;
  while (std::getline(poses, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    int64_t frame = 0;
    int32_t id = 0;
    s >> frame >> id;
    const Eigen::Isometry3d T = rowPose(s);
    if (!s || !T.matrix().allFinite())
      throw Error(poses_path + ":" + std::to_string(line_no) + ": expected frame track_id and 12 numbers");
    auto it = objects.find(id);
    if (it == objects.end())
      throw Error(poses_path + ":" + std::to_string(line_no) + ": track " + std::to_string(id) +
                  " is not in objects.txt");
    it->second.T_world_kobj[frame] = T;
  }
  for (const auto& [key, moving] : motion)
    if (moving)
      if (auto it = objects.find(static_cast<int32_t>(key.second)); it != objects.end()) it->second.parked = false;
  return objects;
}

bool isCar(const TruthObject& o) { return o.type == "Car" || o.type == "Van"; }

double headingErrorDeg(const Eigen::Isometry3d& est, const Eigen::Isometry3d& truth) {
  const Eigen::Vector3d up = truth.linear().col(2);
  auto ground = [&](const Eigen::Vector3d& v) { return (v - up * up.dot(v)).normalized(); };
  const Eigen::Vector3d a = ground(est.linear().col(0)), b = ground(truth.linear().col(0));
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

}  // namespace

Score score(const std::string& run_dir, const Options& options) {
  const RunFolder run = readRunFolder(run_dir);
  const std::string seq = run.dataset_path;
  const fs::path out_root = fs::path(seq).parent_path().parent_path();
  const formats::Trajectory truth_cams =
      formats::readKitti((out_root / "poses" / (run.dataset_sequence + ".txt")).string());
  const formats::Trajectory run_cams = formats::readTum(run_dir + "/trajectory.tum");
  // Frame index of each run pose: times.txt row with the same stamp.
  std::vector<double> times;
  {
    const std::string path = seq + "/times.txt";
    std::ifstream in(path);
    if (!in) throw Error(path + ": cannot open");
    for (double t; in >> t;) times.push_back(t);
  }
  std::vector<int64_t> run_frames;
  for (double stamp : run_cams.stamps) {
    const auto it = std::lower_bound(times.begin(), times.end(), stamp - 1e-6);
    if (it == times.end() || std::abs(*it - stamp) > 1e-4)
      throw Error(run_dir + "/trajectory.tum: time " + std::to_string(stamp) + " is no frame of " + seq + "/times.txt");
    const int64_t frame = it - times.begin();
    if (frame >= static_cast<int64_t>(truth_cams.size()))
      throw Error(run_dir + "/trajectory.tum: frame " + std::to_string(frame) + " has no true camera pose");
    run_frames.push_back(frame);
  }
  if (run_frames.empty()) throw Error(run_dir + "/trajectory.tum: no tracked frame");
  const auto motion = formats::readObjectMotion(seq + "/objects_motion.txt");
  const std::map<int32_t, TruthObject> truth = readTruthObjects(seq, motion);

  Score result;
  // The denominator: parked cars labelled in a tracked frame within view_range.
  std::map<int32_t, bool> parked_in_view;  // track id -> reconstructed correctly
  {
    const std::vector<int64_t> tracked(run_frames.begin(), run_frames.end());
    std::vector<int64_t> sorted = tracked;
    std::sort(sorted.begin(), sorted.end());
    for (const formats::TrackingLabel& l :
         formats::readTrackingLabels(seq + "/label_02/" + run.dataset_sequence + ".txt")) {
      const auto it = truth.find(static_cast<int32_t>(l.track_id));
      if (it == truth.end() || !isCar(it->second) || !it->second.parked) continue;
      if (!std::binary_search(sorted.begin(), sorted.end(), l.frame)) continue;
      if (std::hypot(l.object.p_cam_bottom.x(), l.object.p_cam_bottom.z()) <= options.view_range)
        parked_in_view.emplace(it->first, false);
    }
  }

  const std::string objects_path = run_dir + "/objects.json";
  std::ifstream in(objects_path);
  if (!in) throw Error(objects_path + ": cannot open (did the run have a reconstructor?)");
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw Error(objects_path + ": not JSON (" + e.what() + ")");
  }
  if (!doc.is_object() || !doc.contains("objects") || !doc["objects"].is_array())
    throw Error(objects_path + ": no \"objects\" list");
  for (const auto& entry : doc["objects"]) {
    ObjectResult r;
    Eigen::Isometry3d T_run_obj = Eigen::Isometry3d::Identity();
    try {
      r.track_id = entry.at("track_id").get<int32_t>();
      r.keyframes = entry.value("keyframes", 0);
      const auto T = entry.at("T_world_obj").get<std::vector<double>>();
      if (T.size() != 16) throw Error("T_world_obj has " + std::to_string(T.size()) + " numbers, not 16");
      for (int i = 0; i < 12; ++i) T_run_obj.matrix()(i / 4, i % 4) = T[i];
    } catch (const nlohmann::json::exception& e) {
      throw Error(objects_path + ": object " + std::to_string(result.objects.size()) + ": " + e.what());
    } catch (const Error& e) {
      throw Error(objects_path + ": object " + std::to_string(result.objects.size()) + ": " + e.what());
    }
    if (!T_run_obj.matrix().allFinite())
      throw Error(objects_path + ": object " + std::to_string(r.track_id) + " has a non-finite pose");
    // Local alignment through the nearest tracked camera.
    size_t nearest = 0;
    for (size_t i = 1; i < run_cams.size(); ++i)
      if ((run_cams.poses[i].translation() - T_run_obj.translation()).norm() <
          (run_cams.poses[nearest].translation() - T_run_obj.translation()).norm())
        nearest = i;
    const int64_t f = run_frames[nearest];
    const Eigen::Isometry3d T_true_run = truth_cams.poses[f] * run_cams.poses[nearest].inverse();
    const Eigen::Isometry3d T_true_obj = T_true_run * T_run_obj;
    // Nearest car at frame f.
    const TruthObject* match = nullptr;
    Eigen::Isometry3d T_true_match = Eigen::Isometry3d::Identity();
    double best = options.match_distance;
    for (const auto& [id, o] : truth) {
      if (!isCar(o)) continue;
      const auto p = o.T_world_kobj.find(f);
      if (p == o.T_world_kobj.end()) continue;
      const Eigen::Isometry3d T_landmark = p->second * kittiObjectFromLandmark(o.height);
      const double d = (T_landmark.translation() - T_true_obj.translation()).norm();
      if (d < best) best = d, match = &o, T_true_match = T_landmark;
    }
    ++result.reconstructed;
    if (match) {
      r.truth_track_id = match->track_id;
      r.parked = match->parked;
      const auto m = motion.find({f, match->track_id});
      r.moving = m != motion.end() && m->second;
      r.centre_error_m = best;
      r.yaw_error_deg = headingErrorDeg(T_true_obj, T_true_match);
      r.correct =
          r.parked && r.centre_error_m <= options.centre_tolerance && r.yaw_error_deg <= options.yaw_tolerance_deg;
      if (entry.contains("mesh") && entry["mesh"].is_string()) {
        const Mesh est = formats::readPlyMesh((fs::path(run_dir) / entry["mesh"].get<std::string>()).string());
        char name[32];
        std::snprintf(name, sizeof name, "car_%04d.ply", match->track_id);
        const Mesh true_mesh = formats::readPlyMesh(seq + "/objects/" + name);
        const auto true_samples = surfaceSamples(
            true_mesh, T_true_match * kittiObjectFromLandmark(match->height).inverse(), options.chamfer_samples, true);
        r.chamfer_m = chamfer(surfaceSamples(est, T_true_run, options.chamfer_samples), true_samples);
        r.shape_chamfer_m =
            chamfer(surfaceSamples(est, T_true_match * T_run_obj.inverse(), options.chamfer_samples), true_samples);
      }
    }
    if (r.correct) {
      ++result.correct;
      if (auto it = parked_in_view.find(match->track_id); it != parked_in_view.end()) it->second = true;
    } else if (!match || r.moving) {
      ++result.false_objects;
    } else if (!r.parked) {
      ++result.other;
    }
    result.objects.push_back(r);
  }
  result.parked_in_view = static_cast<int64_t>(parked_in_view.size());
  for (const auto& [id, ok] : parked_in_view) result.parked_in_view_correct += ok ? 1 : 0;
  return result;
}

namespace {

constexpr const char* kUsage =
    "usage: beslam eval-objects --run RUN_DIR [--view-range M] [--match M] [--centre M] [--yaw DEG] [--json FILE]\n"
    "Scores a run's reconstructed objects (objects.json, objects/) against the truth of the synthetic sequence\n"
    "it ran on: parked cars within --view-range (15 m) reconstructed correctly (centre within --centre, 1 m,\n"
    "heading within --yaw, 20 degrees), false objects (no car within --match, 2.5 m, or a moving car), and per\n"
    "object the centre, heading and Chamfer errors. Exit status: 0 success, 1 bad input file, 2 usage error.\n";

double median(std::vector<double> v) {
  if (v.empty()) return -1;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

}  // namespace

int runCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  std::string run, json_path;
  Options options;
  const auto parse = [&] {
    const bool help = cli::forEachValueFlag(args, [&] { out << kUsage; },
                                            {{"--run", cli::text(run)},
                                             {"--json", cli::text(json_path)},
                                             {"--view-range", cli::positive(options.view_range)},
                                             {"--match", cli::positive(options.match_distance)},
                                             {"--centre", cli::positive(options.centre_tolerance)},
                                             {"--yaw", cli::positive(options.yaw_tolerance_deg)}});
    if (!help && run.empty()) throw std::invalid_argument("give --run DIR");
    return help;
  };
  return cli::runSubcommand("eval-objects", err, parse, [&] {
    const Score s = score(run, options);
    std::vector<double> centre, yaw, chamfer, shape;
    for (const ObjectResult& r : s.objects) {
      if (r.truth_track_id < 0 || !r.parked) continue;
      centre.push_back(r.centre_error_m);
      yaw.push_back(r.yaw_error_deg);
      if (r.chamfer_m >= 0) chamfer.push_back(r.chamfer_m), shape.push_back(r.shape_chamfer_m);
    }
    std::ostringstream o;
    o.setf(std::ios::fixed);
    o.precision(3);
    o << "objects reconstructed " << s.reconstructed << ": correct " << s.correct << ", false " << s.false_objects
      << " (" << 100 * s.falseShare() << " %), standing but not parked " << s.other << "\n"
      << "parked cars within " << options.view_range << " m correctly reconstructed " << s.parked_in_view_correct
      << " of " << s.parked_in_view << " (" << 100 * s.correctShare() << " %)\n"
      << "matched parked cars " << centre.size() << ": median centre error " << median(centre) << " m, heading "
      << median(yaw) << " deg, Chamfer " << median(chamfer) << " m (shape alone " << median(shape) << " m)\n";
    out << o.str();
    if (!json_path.empty()) {
      nlohmann::json list = nlohmann::json::array();
      for (const ObjectResult& r : s.objects)
        list.push_back({{"track_id", r.track_id},
                        {"truth_track_id", r.truth_track_id},
                        {"parked", r.parked},
                        {"moving", r.moving},
                        {"correct", r.correct},
                        {"centre_error_m", r.centre_error_m},
                        {"yaw_error_deg", r.yaw_error_deg},
                        {"chamfer_m", r.chamfer_m},
                        {"shape_chamfer_m", r.shape_chamfer_m},
                        {"keyframes", r.keyframes}});
      const nlohmann::json j = {{"run", run},
                                {"reconstructed", s.reconstructed},
                                {"correct", s.correct},
                                {"false", s.false_objects},
                                {"standing_not_parked", s.other},
                                {"parked_in_view", s.parked_in_view},
                                {"parked_in_view_correct", s.parked_in_view_correct},
                                {"view_range_m", options.view_range},
                                {"median_centre_error_m", median(centre)},
                                {"median_yaw_error_deg", median(yaw)},
                                {"median_chamfer_m", median(chamfer)},
                                {"median_shape_chamfer_m", median(shape)},
                                {"objects", list}};
      writeFileAtomic(json_path, j.dump(2) + "\n");
    }
    return 0;
  });
}

}  // namespace beslam::object_score
