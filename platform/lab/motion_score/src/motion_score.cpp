#include "beslam/motion_score/motion_score.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/common/run_folder.hpp"
#include "beslam/datasets/labels.hpp"
#include "beslam/sdk/cli_args.hpp"

namespace beslam::motion_score {
namespace {

struct Detection {
  datasets::TrackingLabel label;
  std::string state;  // static | dynamic | unknown
};

bool carLike(const std::string& type) { return type == "Car" || type == "Van" || type == "Truck"; }

// objects.txt: a tracking row (datasets::formatTrackingRow) and the motion state as a last word.
std::map<int64_t, std::vector<Detection>> readObjects(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open (a run writes objects.txt when its pipeline has a detector)");
  std::map<int64_t, std::vector<Detection>> out;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const size_t cut = line.find_last_of(' ');
    if (cut == std::string::npos) throwAt(path, "expected a tracking row and a motion state", line_no);
    Detection d;
    d.state = line.substr(cut + 1);
    if (!d.state.empty() && d.state.back() == '\r') d.state.pop_back();
    if (d.state != "static" && d.state != "dynamic" && d.state != "unknown")
      throwAt(path, "motion state '" + d.state + "' is none of static, dynamic, unknown", line_no);
    d.label = datasets::parseTrackingRow(line.substr(0, cut), path, line_no);
    out[d.label.frame].push_back(std::move(d));
  }
  return out;
}

double bevDistance(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::hypot(a.x() - b.x(), a.z() - b.z());
}

}  // namespace

double Counts::f1() const {
  const double p = tp + fp ? double(tp) / double(tp + fp) : 0.0;
  const double r = tp + fn ? double(tp) / double(tp + fn) : 0.0;
  return p + r > 0 ? 2 * p * r / (p + r) : 0.0;
}

Counts score(const std::string& objects_path, const std::string& labels_path, const std::string& motion_path,
             const Options& options) {
  const auto detections = readObjects(objects_path);
  std::map<int64_t, std::vector<datasets::TrackingLabel>> labels;
  for (auto& l : datasets::readTrackingLabels(labels_path))
    if (carLike(l.object.type)) labels[l.frame].push_back(std::move(l));
  const auto moving = datasets::readObjectMotion(motion_path);

  Counts c;
  for (const auto& [frame, dets] : detections) {
    const auto lit = labels.find(frame);
    std::vector<bool> claimed(lit == labels.end() ? 0 : lit->second.size(), false);
    for (const Detection& d : dets) {
      if (!carLike(d.label.object.type)) continue;
      ++c.detections;
      if (lit == labels.end()) continue;
      int best = -1;
      double best_d = options.match_distance;
      for (size_t j = 0; j < lit->second.size(); ++j) {
        const double dist = bevDistance(d.label.object.p_cam_bottom, lit->second[j].object.p_cam_bottom);
        if (!claimed[j] && dist < best_d) best = static_cast<int>(j), best_d = dist;
      }
      if (best < 0) continue;
      claimed[best] = true;
      const datasets::TrackingLabel& truth = lit->second[best];
      const Eigen::Vector3d& p = truth.object.p_cam_bottom;
      const double range = std::hypot(p.x(), p.z());
      if (range > options.max_range) continue;
      const auto m = moving.find({frame, truth.track_id});
      if (m == moving.end())
        throw Error(motion_path + ": no row for frame " + std::to_string(frame) + ", track " +
                    std::to_string(truth.track_id) + " of " + labels_path);
      ++c.matched;
      if (m->second) {
        ++c.moving;
        if (d.state == "dynamic")
          ++c.tp;
        else
          ++c.fn, ++(d.state == "static" ? c.moving_static : c.moving_unknown);
      } else {
        ++c.standing;
        if (d.state == "dynamic") ++c.fp, ++c.standing_dynamic;
        if (d.state == "unknown") ++c.standing_unknown;
        if (range <= options.static_range) {
          ++c.standing_near;
          if (d.state == "static") ++c.standing_near_static;
        }
      }
    }
  }
  return c;
}

namespace {

constexpr const char* kUsage =
    "usage: beslam eval-motion --objects RUN/objects.txt --labels LABEL_02.txt --motion objects_motion.txt\n"
    "                          [--max-range M] [--static-range M] [--match M] [--json FILE]\n"
    "       beslam eval-motion --run RUN_DIR [options]   (a run on a synthetic sequence: the truth files are\n"
    "                          found through its summary.json)\n"
    "Scores the motion states a run wrote against the truth of a synthetic sequence: F1 of 'dynamic',\n"
    "moving cars called static, standing cars called dynamic, standing cars within --static-range (30 m)\n"
    "called static. Exit status: 0 success, 1 bad input file, 2 usage error.\n";

}  // namespace

int runCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  std::string objects, labels, motion, run, json_path;
  Options options;
  try {
    const bool help = cli::forEachFlag(
        args, [&] { out << kUsage; },
        [&](const std::string& a, size_t& i) {
          auto text = [&] { return cli::nextValue(args, i); };
          auto number = [&] { return cli::nextPositiveNumber(args, i); };
          if (a == "--objects")
            objects = text();
          else if (a == "--labels")
            labels = text();
          else if (a == "--motion")
            motion = text();
          else if (a == "--run")
            run = text();
          else if (a == "--json")
            json_path = text();
          else if (a == "--max-range")
            options.max_range = number();
          else if (a == "--static-range")
            options.static_range = number();
          else if (a == "--match")
            options.match_distance = number();
          else
            throw std::invalid_argument("unknown argument '" + a + "'");
        });
    if (help) return 0;
    if (run.empty() && (objects.empty() || labels.empty() || motion.empty()))
      throw std::invalid_argument("give --run DIR, or --objects, --labels and --motion");
  } catch (const std::invalid_argument& e) {
    err << "beslam eval-motion: " << e.what() << " (see beslam eval-motion --help)\n";
    return 2;
  }
  try {
    if (!run.empty()) {
      const RunFolder folder = readRunFolder(run);
      if (objects.empty()) objects = run + "/objects.txt";
      if (labels.empty()) labels = folder.dataset_path + "/label_02/" + folder.dataset_sequence + ".txt";
      if (motion.empty()) motion = folder.dataset_path + "/objects_motion.txt";
    }
    const Counts c = score(objects, labels, motion, options);
    std::ostringstream s;
    s.setf(std::ios::fixed);
    s.precision(4);
    s << "car detections " << c.detections << ", matched to truth " << c.matched << "\n"
      << "F1(dynamic) " << c.f1() << " (TP " << c.tp << ", FP " << c.fp << ", FN " << c.fn << ")\n"
      << "moving called static " << 100 * c.movingCalledStatic() << " % (" << c.moving_static << " of " << c.moving
      << "; unknown " << c.moving_unknown << ")\n"
      << "standing called dynamic " << 100 * c.standingCalledDynamic() << " % (" << c.standing_dynamic << " of "
      << c.standing << "; unknown " << c.standing_unknown << ")\n"
      << "standing within " << options.static_range << " m called static " << 100 * c.standingNearCalledStatic()
      << " % (" << c.standing_near_static << " of " << c.standing_near << ")\n";
    out << s.str();
    if (!json_path.empty()) {
      nlohmann::json j = {{"objects", objects},
                          {"labels", labels},
                          {"motion", motion},
                          {"detections", c.detections},
                          {"matched", c.matched},
                          {"f1_dynamic", c.f1()},
                          {"tp", c.tp},
                          {"fp", c.fp},
                          {"fn", c.fn},
                          {"moving", c.moving},
                          {"moving_static", c.moving_static},
                          {"moving_unknown", c.moving_unknown},
                          {"standing", c.standing},
                          {"standing_dynamic", c.standing_dynamic},
                          {"standing_unknown", c.standing_unknown},
                          {"standing_near", c.standing_near},
                          {"standing_near_static", c.standing_near_static},
                          {"static_range_m", options.static_range}};
      writeFileAtomic(json_path, j.dump(2) + "\n");
    }
    return 0;
  } catch (const std::exception& e) {
    err << "beslam eval-motion: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace beslam::motion_score
