#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <unordered_map>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/datasets/labels.hpp"
#include "beslam/sdk/cli_args.hpp"
#include "beslam/static_map/score.hpp"
#include "beslam/static_map/static_map.hpp"
#include "beslam/trajectory/trajectory.hpp"

namespace fs = std::filesystem;

namespace beslam::static_map {

namespace {

// The lowest part of a box is road and kerb (label boxes sit a few centimetres into an uneven road): a
// trail is what a moving object leaves above it.
constexpr double kGroundBand = 0.3;  // metres

bool carLike(const std::string& type) { return type == "Car" || type == "Van" || type == "Truck"; }

struct WorldBox {
  Eigen::Isometry3d T_box_world;  // world -> box frame (x length, y height, z width)
  Eigen::Vector3d half;           // half extents in the box frame
  Eigen::AlignedBox3d aabb;       // world
};

WorldBox worldBox(const datasets::ObjectLabel& o, const Eigen::Isometry3d& T_world_cam) {
  Eigen::Isometry3d T_cam_box = Eigen::Isometry3d::Identity();
  T_cam_box.linear() = Eigen::AngleAxisd(o.ry, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_cam_box.translation() = o.p_cam_bottom - Eigen::Vector3d(0, o.h / 2, 0);  // centre (y down)
  WorldBox b;
  const Eigen::Isometry3d T_world_box = T_world_cam * T_cam_box;
  b.T_box_world = T_world_box.inverse();
  b.half = Eigen::Vector3d(o.l / 2, o.h / 2, o.w / 2);
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner((i & 1) ? b.half.x() : -b.half.x(), (i & 2) ? b.half.y() : -b.half.y(),
                                 (i & 4) ? b.half.z() : -b.half.z());
    b.aabb.extend(T_world_box * corner);
  }
  return b;
}

// Occupied voxel centres at the tree's resolution, in the truth frame, hashed by 2 m cells.
class VoxelIndex {
 public:
  VoxelIndex(const octomap::OcTree& tree, const Similarity& s) {
    const double res = tree.getResolution();
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
      if (!tree.isNodeOccupied(*it)) continue;
      const double size = it.getSize();
      const int n = std::max(1, static_cast<int>(std::lround(size / res)));
      const octomap::point3d c = it.getCoordinate();
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
          for (int k = 0; k < n; ++k) {  // a pruned leaf covers n^3 voxels
            const Eigen::Vector3d p(c.x() + (i - (n - 1) / 2.0) * res, c.y() + (j - (n - 1) / 2.0) * res,
                                    c.z() + (k - (n - 1) / 2.0) * res);
            centres_.push_back(s.scale * (s.R * p) + s.t);
            cells_[cellKey(centres_.back())].push_back(centres_.size() - 1);
          }
    }
  }
  size_t size() const { return centres_.size(); }
  // Indices of voxels whose centre lies inside b shrunk by `inset`, and at least `above_bottom` over
  // the box's bottom face.
  template <class F>
  void forEachInside(const WorldBox& b, double inset, F&& f, double above_bottom = 0) const {
    const Eigen::Vector3i lo = cell(b.aabb.min()), hi = cell(b.aabb.max());
    for (int x = lo.x(); x <= hi.x(); ++x)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int z = lo.z(); z <= hi.z(); ++z) {
          const auto found = cells_.find(key(x, y, z));
          if (found == cells_.end()) continue;
          for (size_t i : found->second) {
            const Eigen::Vector3d q = b.T_box_world * centres_[i];
            if (std::abs(q.x()) <= b.half.x() - inset && std::abs(q.y()) <= b.half.y() - inset &&
                std::abs(q.z()) <= b.half.z() - inset && b.half.y() - q.y() >= above_bottom)  // y down
              f(i);
          }
        }
  }

 private:
  static constexpr double kCell = 2.0;
  static Eigen::Vector3i cell(const Eigen::Vector3d& p) { return (p / kCell).array().floor().cast<int>(); }
  static int64_t key(int x, int y, int z) {
    return (int64_t(x & 0x1fffff) << 42) | (int64_t(y & 0x1fffff) << 21) | int64_t(z & 0x1fffff);
  }
  static int64_t cellKey(const Eigen::Vector3d& p) {
    const Eigen::Vector3i c = cell(p);
    return key(c.x(), c.y(), c.z());
  }
  std::vector<Eigen::Vector3d> centres_;
  std::unordered_map<int64_t, std::vector<size_t>> cells_;
};

}  // namespace

MapScore scoreStaticMap(const octomap::OcTree& tree, const std::string& sequence_dir, const std::string& sequence,
                        const Similarity& map_to_truth, double near) {
  const std::string labels_path = (fs::path(sequence_dir) / "label_02" / (sequence + ".txt")).string();
  const std::string motion_path = (fs::path(sequence_dir) / "objects_motion.txt").string();
  const std::string poses_path =
      (fs::path(sequence_dir).parent_path().parent_path() / "poses" / (sequence + ".txt")).string();
  const auto labels = datasets::readTrackingLabels(labels_path);
  const auto moving = datasets::readObjectMotion(motion_path);
  const trajectory::Trajectory poses = trajectory::readKitti(poses_path);

  std::set<int64_t> ever_moving;
  for (const auto& [key, m] : moving)
    if (m) ever_moving.insert(key.second);

  const VoxelIndex voxels(tree, map_to_truth);
  const double inset = tree.getResolution() / 2;
  // A voxel is on a trail when it lies in a car's box at a frame where the car moves, and in no
  // object's box at a frame where that object stands (a car that parked there, a standing pedestrian:
  // mapping those is right).
  std::vector<char> in_path(voxels.size(), 0), in_standing(voxels.size(), 0), in_parked(voxels.size(), 0);
  std::set<int64_t> parked_near, parked_mapped;
  for (const datasets::TrackingLabel& l : labels) {
    if (l.object.isDontCare() || l.frame < 0 || static_cast<size_t>(l.frame) >= poses.size()) continue;
    const WorldBox b = worldBox(l.object, poses.poses[static_cast<size_t>(l.frame)]);
    const auto m = moving.find({l.frame, l.track_id});
    if (m != moving.end() && m->second) {
      if (carLike(l.object.type))
        voxels.forEachInside(
            b, inset, [&](size_t i) { in_path[i] = 1; }, kGroundBand);
      continue;
    }
    voxels.forEachInside(b, -inset, [&](size_t i) { in_standing[i] = 1; });  // generous: touching counts
    if (carLike(l.object.type) && !ever_moving.count(l.track_id)) {
      const double range = std::hypot(l.object.p_cam_bottom.x(), l.object.p_cam_bottom.z());
      if (range <= near) parked_near.insert(l.track_id);
      voxels.forEachInside(b, inset, [&](size_t i) {
        in_parked[i] = 1;
        if (range <= near) parked_mapped.insert(l.track_id);
      });
    }
  }
  MapScore score;
  score.occupied = static_cast<int64_t>(voxels.size());
  for (size_t i = 0; i < voxels.size(); ++i) {
    score.in_moving_paths += in_path[i] && !in_standing[i];
    score.in_parked_cars += in_parked[i];
  }
  score.parked_cars = static_cast<int64_t>(parked_near.size());
  score.parked_cars_mapped = static_cast<int64_t>(parked_mapped.size());
  return score;
}

namespace {

constexpr const char* kUsage =
    "usage: beslam eval-static-map --run RUN_DIR [--near M] [--json FILE]\n"
    "Scores a run's static_map.bt (output.octomap) against the truth of the synthetic sequence it ran on:\n"
    "occupied voxels inside moving cars' boxes (ghost trails), inside parked cars' boxes, and parked cars\n"
    "within --near metres (default 20) with voxels. Exit status: 0 success, 1 bad input file, 2 usage error.\n";

Similarity alignmentOf(const nlohmann::json& summary) {
  Similarity s;
  const auto ev = summary.find("evaluation");
  if (ev == summary.end() || !ev->contains("alignment")) return s;
  const auto& a = (*ev)["alignment"];
  s.scale = a.value("scale", 1.0);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) s.R(r, c) = a["rotation"][r][c].get<double>();
    s.t(r) = a["translation"][r].get<double>();
  }
  return s;
}

}  // namespace

int runEvalCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  std::string run, json_path;
  double near = 20.0;
  const auto parse = [&] {
    const bool help = cli::forEachValueFlag(
        args, [&] { out << kUsage; },
        {{"--run", cli::text(run)}, {"--json", cli::text(json_path)}, {"--near", cli::positive(near)}});
    if (!help && run.empty()) throw std::invalid_argument("give --run DIR");
    return help;
  };
  return cli::runSubcommand("eval-static-map", err, parse, [&] {
    const std::string summary_path = (fs::path(run) / "summary.json").string();
    nlohmann::json summary;
    try {
      summary = nlohmann::json::parse(readFile(summary_path));
    } catch (const nlohmann::json::exception& e) {
      throw Error(summary_path + ": not JSON (" + e.what() + ")");
    }
    const std::string seq = summary.value("dataset_path", "");
    if (seq.empty()) throw Error(summary_path + ": no dataset_path (not a run on a KITTI-layout sequence)");
    const auto tree = readTree((fs::path(run) / "static_map.bt").string());
    const MapScore s = scoreStaticMap(*tree, seq, summary.value("dataset_sequence", "00"), alignmentOf(summary), near);
    out << "occupied voxels " << s.occupied << " (" << tree->getResolution() << " m)\n"
        << "in moving cars' paths " << s.in_moving_paths << "\n"
        << "in parked cars " << s.in_parked_cars << "; parked cars within " << near << " m with voxels "
        << s.parked_cars_mapped << " of " << s.parked_cars << "\n";
    if (!json_path.empty())
      writeFileAtomic(json_path, nlohmann::json{{"run", run},
                                                {"resolution_m", tree->getResolution()},
                                                {"occupied", s.occupied},
                                                {"in_moving_paths", s.in_moving_paths},
                                                {"in_parked_cars", s.in_parked_cars},
                                                {"parked_cars_near", s.parked_cars},
                                                {"parked_cars_near_mapped", s.parked_cars_mapped},
                                                {"near_m", near}}
                                         .dump(2) +
                                     "\n");
    return 0;
  });
}

}  // namespace beslam::static_map
