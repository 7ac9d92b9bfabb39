// Run data for the HTML report: trajectories against ground truth, error and scale over time, timing,
// detections, the map; written as data/run_K.js beside index.html and the copied libraries.
#include "beslam/report/report.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/formats/ply.hpp"
#include "beslam/trajectory/trajectory.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace beslam::report {

extern const char* const kPageTemplate;  // assets/report.html, embedded at build time

namespace {

constexpr size_t kMaxSeries = 2000;  // points a time series keeps (evenly spaced)
constexpr size_t kMaxSamples = 12;   // sample frames a run shows

double r3(double x) { return std::round(x * 1000.0) / 1000.0; }
double r2(double x) { return std::round(x * 100.0) / 100.0; }

struct Pose {
  double stamp;
  Eigen::Vector3d p;
  Eigen::Matrix3d R;
};

std::vector<double> readTimes(const fs::path& path) {
  std::vector<double> t;
  std::ifstream in(path);
  for (double x; in >> x;) t.push_back(x);
  return t;
}

// Index of the stamp nearest to t within 1 ms, or -1.
long nearest(const std::vector<double>& stamps, double t) {
  const auto it = std::lower_bound(stamps.begin(), stamps.end(), t);
  long best = -1;
  double bd = 1e-3;
  for (auto j : {it - stamps.begin() - 1, it - stamps.begin()})
    if (j >= 0 && j < static_cast<long>(stamps.size()) && std::abs(stamps[j] - t) <= bd)
      bd = std::abs(stamps[j] - t), best = j;
  return best;
}

// The run's object meshes (objects.json, objects/*.ply; world frame), each simplified by vertex
// clustering on a 0.12 m grid (a car keeps its shape at a few hundred triangles, so a run with dozens of
// cars stays a few MB).
json readObjectMeshes(const fs::path& run) {
  json out = json::array();
  const fs::path listing = run / "objects.json";
  if (!fs::exists(listing)) return out;
  json doc;
  try {
    doc = json::parse(readFile(listing.string()));
  } catch (const json::exception& e) {
    throw Error(listing.string() + ": not JSON (" + e.what() + ")");
  }
  constexpr double kCell = 0.12;
  for (const json& o : doc.value("objects", json::array())) {
    if (!o.contains("mesh") || !o["mesh"].is_string()) continue;
    const formats::TriangleMesh mesh = formats::readPlyMesh((run / o["mesh"].get<std::string>()).string());
    std::map<std::array<long, 3>, int> cell_index;
    std::vector<Eigen::Vector3d> sum;
    std::vector<int> count, remap(mesh.vertices.size());
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      const Eigen::Vector3d& v = mesh.vertices[i];
      const std::array<long, 3> cell = {std::lround(std::floor(v.x() / kCell)), std::lround(std::floor(v.y() / kCell)),
                                        std::lround(std::floor(v.z() / kCell))};
      const auto [it, fresh] = cell_index.emplace(cell, static_cast<int>(sum.size()));
      if (fresh) sum.emplace_back(Eigen::Vector3d::Zero()), count.push_back(0);
      sum[it->second] += v, ++count[it->second];
      remap[i] = it->second;
    }
    json positions = json::array(), indices = json::array();
    for (size_t k = 0; k < sum.size(); ++k) {
      const Eigen::Vector3d c = sum[k] / count[k];
      positions.push_back(r2(c.x())), positions.push_back(r2(c.y())), positions.push_back(r2(c.z()));
    }
    for (const auto& f : mesh.faces) {
      const int a = remap[f[0]], b = remap[f[1]], c = remap[f[2]];
      if (a != b && b != c && a != c) indices.push_back(a), indices.push_back(b), indices.push_back(c);
    }
    out.push_back({{"track", o.value("track_id", -1)}, {"positions", positions}, {"indices", indices}});
  }
  return out;
}

json readMap(const fs::path& ply, size_t max_points) {
  std::ifstream in(ply);
  if (!in) return nullptr;
  std::string line;
  size_t count = 0;
  std::vector<std::string> props;
  bool ascii = false;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string w;
    ls >> w;
    if (w == "format") {
      std::string f;
      ls >> f;
      ascii = f == "ascii";
    } else if (w == "element") {
      std::string e;
      ls >> e >> count;
      if (e != "vertex") throwAt(ply.string(), "unexpected element '" + e + "' (expected vertex)");
    } else if (w == "property") {
      std::string type, name;
      ls >> type >> name;
      props.push_back(name);
    } else if (w == "end_header")
      break;
  }
  if (!ascii) throwAt(ply.string(), "only ASCII PLY is read (the runner writes ASCII)");
  auto idx = [&](const char* n) {
    const auto it = std::find(props.begin(), props.end(), n);
    return it == props.end() ? -1 : static_cast<int>(it - props.begin());
  };
  const int ix = idx("x"), iy = idx("y"), iz = idx("z"), ir = idx("red"), ig = idx("green"), ib = idx("blue");
  if (ix < 0 || iy < 0 || iz < 0) throwAt(ply.string(), "no x, y, z vertex properties");
  const size_t stride = std::max<size_t>(1, (count + max_points - 1) / std::max<size_t>(1, max_points));
  json pos = json::array(), col = json::array();
  std::vector<double> v(props.size());
  for (size_t k = 0; k < count && std::getline(in, line); ++k) {
    if (k % stride) continue;
    std::istringstream ls(line);
    for (auto& x : v) ls >> x;
    if (!ls)
      throwAt(ply.string(), "vertex " + std::to_string(k) + ": expected " + std::to_string(props.size()) + " numbers");
    pos.push_back(r2(v[ix])), pos.push_back(r2(v[iy])), pos.push_back(r2(v[iz]));
    if (ir >= 0 && ig >= 0 && ib >= 0) col.push_back(int(v[ir])), col.push_back(int(v[ig])), col.push_back(int(v[ib]));
  }
  return {{"positions", pos}, {"colors", col}, {"total", count}, {"shown", pos.size() / 3}};
}

// Evenly thinned indices 0..n-1 (at most kMaxSeries).
std::vector<size_t> thin(size_t n) {
  std::vector<size_t> k;
  const size_t step = std::max<size_t>(1, (n + kMaxSeries - 1) / kMaxSeries);
  for (size_t i = 0; i < n; i += step) k.push_back(i);
  return k;
}

json timingData(const fs::path& csv) {
  std::ifstream in(csv);
  if (!in) return nullptr;
  std::string line;
  std::getline(in, line);
  std::vector<std::string> cols;
  {
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cols.push_back(c);
  }
  if (cols.empty() || cols.front() != "frame")
    throwAt(csv.string(), "not a timing.csv: the header must start with 'frame' (as beslam run writes it)", 1);
  std::vector<std::vector<double>> values(cols.size());
  std::vector<double> frame, total;
  const auto total_it = std::find(cols.begin(), cols.end(), "total_ms");
  const int ti = total_it == cols.end() ? -1 : static_cast<int>(total_it - cols.begin());
  for (int row = 2; std::getline(in, line); ++row) {
    if (line.empty()) continue;
    const size_t fields = static_cast<size_t>(std::count(line.begin(), line.end(), ',')) + 1;
    if (fields != cols.size())
      throwAt(csv.string(),
              "a row of " + std::to_string(fields) + " fields under a header of " + std::to_string(cols.size()), row);
    std::stringstream ss(line);
    int c = 0;
    for (std::string f; std::getline(ss, f, ','); ++c) {
      if (f.empty() || c >= static_cast<int>(cols.size())) continue;
      char* end = nullptr;
      const double x = std::strtod(f.c_str(), &end);
      if (end == f.c_str()) throwAt(csv.string(), "'" + f + "' is not a number", row);
      values[c].push_back(x);
      if (c == 0) frame.push_back(x);
      if (c == ti) total.push_back(x);
    }
  }
  json stages = json::array();
  for (size_t c = 1; c < cols.size(); ++c) {
    const bool stage = cols[c].size() > 3 && cols[c].compare(cols[c].size() - 3, 3, "_ms") == 0;
    if (!stage || cols[c] == "total_ms" || values[c].empty()) continue;  // not rss_mb
    std::vector<double> v = values[c];
    std::sort(v.begin(), v.end());
    const double med = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    double sum = 0;
    for (double x : v) sum += x;
    std::string name = cols[c].substr(0, cols[c].size() - 3);
    stages.push_back({{"name", name}, {"median", r3(med)}, {"mean", r3(sum / v.size())}, {"frames", v.size()}});
  }
  json f = json::array(), t = json::array();
  if (total.size() == frame.size())
    for (size_t k : thin(frame.size())) f.push_back(frame[k]), t.push_back(r2(total[k]));
  return {{"stages", stages}, {"frame", f}, {"total", t}};
}

Eigen::Matrix3d rotY(double a) {
  Eigen::Matrix3d R;
  R << std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a);
  return R;
}

}  // namespace

namespace {

// The summary figures the page shows; what the page cannot show goes to `warnings`, said once here
// rather than by empty plots.
json summaryData(const fs::path& run, const json& summary, std::vector<std::string>* warnings) {
  const fs::path summary_path = run / "summary.json";
  if (warnings) {
    if (summary.contains("status") && summary["status"].is_string() && summary["status"] != "completed")
      warnings->push_back(summary_path.string() + ": the run did not complete (" +
                          summary["status"].get<std::string>() + "); the report shows what it left");
    if (!fs::exists(run / "trajectory.tum"))
      warnings->push_back((run / "trajectory.tum").string() +
                          ": missing; the trajectory, APE and scale plots are empty");
    if (!fs::exists(run / "timing.csv"))
      warnings->push_back((run / "timing.csv").string() + ": missing; the timing plot is empty");
  }
  json d;
  for (const char* k : {"pipeline", "dataset", "frames", "tracked", "keyframes", "median_frame_ms", "ape", "detections",
                        "world", "map_points", "plugins", "frames_with_masks", "untracked_frames"})
    if (summary.contains(k)) d[k] = summary[k];
  if (summary.contains("evaluation")) {
    const json& ev = summary["evaluation"];
    for (const char* k : {"ape", "rpe"})
      if (ev.contains(k) && ev[k].contains("trans")) d["eval_" + std::string(k) + "_trans"] = ev[k]["trans"];
    if (ev.contains("alignment"))
      d["alignment"] = {{"type", ev["alignment"].value("type", "")}, {"scale", ev["alignment"].value("scale", 1.0)}};
  }
  return d;
}

// The estimated trajectory (the map's frame), empty without trajectory.tum.
std::vector<Pose> readEstimate(const fs::path& run) {
  std::vector<Pose> est;
  if (fs::exists(run / "trajectory.tum")) {
    const trajectory::Trajectory t = trajectory::readTum((run / "trajectory.tum").string());
    for (size_t i = 0; i < t.size(); ++i) est.push_back({t.stamps[i], t.poses[i].translation(), t.poses[i].linear()});
  }
  return est;
}

// Ground truth of the KITTI layout the summary names, and its frame stamps; `note` says why there is none.
struct GroundTruth {
  std::vector<double> times;
  std::vector<Pose> poses;
  std::string note;
};

GroundTruth readGroundTruth(const json& summary) {
  GroundTruth g;
  if (!summary.contains("dataset_path") || !summary["dataset_path"].is_string()) {
    g.note = "the summary names no KITTI dataset path";
    return g;
  }
  const fs::path seq = summary["dataset_path"].get<std::string>();
  g.times = readTimes(seq / "times.txt");
  const fs::path poses = seq.parent_path().parent_path() / "poses" / (seq.filename().string() + ".txt");
  if (fs::exists(poses) && !g.times.empty()) {
    const trajectory::Trajectory t = trajectory::readKitti(poses.string());
    for (size_t i = 0; i < t.size() && i < g.times.size(); ++i)
      g.poses.push_back({g.times[i], t.poses[i].translation(), t.poses[i].linear()});
  } else {
    g.note = "no ground truth at " + poses.string();
  }
  return g;
}

// The alignment of the run's own evaluation: p_gt = scale R p_est + t.
struct Alignment {
  double scale = 1;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
};

Alignment alignmentOf(const json& summary) {
  Alignment al;
  if (summary.contains("evaluation") && summary["evaluation"].contains("alignment")) {
    const json& a = summary["evaluation"]["alignment"];
    al.scale = a.value("scale", 1.0);
    for (int i = 0; i < 3; ++i) {
      al.t[i] = a["translation"][i].get<double>();
      for (int j = 0; j < 3; ++j) al.R(i, j) = a["rotation"][i][j].get<double>();
    }
  }
  return al;
}

std::vector<double> stampsOf(const std::vector<Pose>& poses) {
  std::vector<double> stamps;
  for (const auto& p : poses) stamps.push_back(p.stamp);
  return stamps;
}

// The plotted series: the aligned estimate against the truth (top view), APE and scale over time.
json seriesData(const std::vector<Pose>& est, const GroundTruth& gt, const Alignment& a) {
  const std::vector<double> gt_stamps = stampsOf(gt.poses);
  // Paired series: frame index, aligned estimate, ground truth.
  std::vector<long> frame;
  std::vector<Eigen::Vector3d> al, raw, ref;
  for (const auto& p : est) {
    const long g = gt.poses.empty() ? -1 : nearest(gt_stamps, p.stamp);
    if (g < 0) continue;
    frame.push_back(g);
    al.push_back(a.scale * (a.R * p.p) + a.t);
    raw.push_back(p.p);
    ref.push_back(gt.poses[g].p);
  }
  json top = {{"est", json::array()},           {"gt", json::array()},
              {"frame", json::array()},         {"ape", json::array()},
              {"scale_aligned", json::array()}, {"scale_raw", json::array()},
              {"scale_frame", json::array()}};
  for (size_t k : thin(al.size())) {
    top["frame"].push_back(frame[k]);
    top["est"].push_back({r3(al[k].x()), r3(al[k].z())});
    top["ape"].push_back(r3((al[k] - ref[k]).norm()));
  }
  for (size_t k : thin(gt.poses.size())) top["gt"].push_back({r3(gt.poses[k].p.x()), r3(gt.poses[k].p.z())});
  // Scale over time: distance travelled by the estimate over that of the truth, in a window of 20 frames
  // (after the run's alignment, and as run); windows where the truth moved under 1 m are left out.
  constexpr size_t W = 20;
  std::vector<double> sa, sr;
  std::vector<long> sf;
  for (size_t i = W; i < al.size(); ++i) {
    double da = 0, dr = 0, dg = 0;
    for (size_t j = i - W + 1; j <= i; ++j)
      da += (al[j] - al[j - 1]).norm(), dr += (raw[j] - raw[j - 1]).norm(), dg += (ref[j] - ref[j - 1]).norm();
    if (dg < 1.0) continue;
    sa.push_back(da / dg), sr.push_back(dr / dg), sf.push_back(frame[i]);
  }
  for (size_t k : thin(sf.size()))
    top["scale_frame"].push_back(sf[k]), top["scale_aligned"].push_back(r3(sa[k])),
        top["scale_raw"].push_back(r3(sr[k]));
  top["window"] = W;
  top["note"] = gt.note;
  return top;
}

// Detections per frame (d["counts"]) and one box per object track, its last observation in the map's
// frame (d["boxes"]), from objects.txt; nothing without it.
void detectionData(const fs::path& run, const std::vector<double>& times, const std::vector<Pose>& est, json& d) {
  if (!fs::exists(run / "objects.txt")) return;
  const std::vector<double> est_stamps = stampsOf(est);
  std::ifstream in(run / "objects.txt");
  std::map<long, std::array<int, 3>> per_frame;
  std::map<long, std::pair<long, std::vector<double>>> last;  // track -> (frame, h w l x y z ry)
  std::map<long, std::string> last_state;
  std::string line;
  for (int row = 1; std::getline(in, line); ++row) {
    std::istringstream ls(line);
    std::vector<std::string> f;
    for (std::string w; ls >> w;) f.push_back(w);
    if (f.size() < 19) continue;
    const long fr = std::stol(f[0]), track = std::stol(f[1]);
    const std::string& st = f.back();
    auto& c = per_frame[fr];
    c[st == "static" ? 0 : st == "dynamic" ? 1 : 2]++;
    if (track >= 0) {
      std::vector<double> b;
      for (int k = 10; k <= 16; ++k) b.push_back(std::stod(f[k]));
      last[track] = {fr, b};
      last_state[track] = st;
    }
  }
  json cf = json::array(), cs = json::array(), cd = json::array(), cu = json::array();
  std::vector<long> frames;
  for (const auto& kv : per_frame) frames.push_back(kv.first);
  for (size_t k : thin(frames.size())) {
    const auto& c = per_frame[frames[k]];
    cf.push_back(frames[k]), cs.push_back(c[0]), cd.push_back(c[1]), cu.push_back(c[2]);
  }
  d["counts"] = {{"frame", cf}, {"static", cs}, {"dynamic", cd}, {"unknown", cu}};
  json boxes = json::array();
  for (const auto& [track, fb] : last) {
    if (fb.first < 0 || fb.first >= static_cast<long>(times.size())) continue;
    const long e = nearest(est_stamps, times[fb.first]);
    if (e < 0) continue;
    const auto& b = fb.second;  // h w l x y z ry, bottom centre in the camera frame
    json corners = json::array();
    for (int k = 0; k < 8; ++k) {
      const double x = (k == 0 || k == 1 || k == 4 || k == 5 ? 0.5 : -0.5) * b[2];
      const double z = (k == 0 || k == 3 || k == 4 || k == 7 ? 0.5 : -0.5) * b[1];
      const double y = k < 4 ? 0.0 : -b[0];
      const Eigen::Vector3d pc = rotY(b[6]) * Eigen::Vector3d(x, y, z) + Eigen::Vector3d(b[3], b[4], b[5]);
      const Eigen::Vector3d pw = est[e].R * pc + est[e].p;
      corners.push_back(r2(pw.x())), corners.push_back(r2(pw.y())), corners.push_back(r2(pw.z()));
    }
    boxes.push_back({{"track", track}, {"state", last_state[track]}, {"corners", corners}});
    if (boxes.size() >= 1000) break;
  }
  d["boxes"] = boxes;
}

// The 3D view: map points, trajectory, keyframes (camera centres and optical axes), ground truth
// brought into the map's frame (inverse of the alignment).
json viewData(const fs::path& run, const std::vector<Pose>& est, const GroundTruth& gt, const Alignment& a,
              size_t max_points) {
  json view;
  view["map"] = readMap(run / "map_points.ply", max_points);
  view["objects"] = readObjectMeshes(run);
  json path = json::array();
  for (size_t k : thin(est.size()))
    path.push_back(r2(est[k].p.x())), path.push_back(r2(est[k].p.y())), path.push_back(r2(est[k].p.z()));
  view["trajectory"] = path;
  json kfs = json::array();
  if (fs::exists(run / "keyframes.tum")) {
    const trajectory::Trajectory k = trajectory::readTum((run / "keyframes.tum").string());
    for (size_t i = 0; i < k.size(); ++i) {
      const Eigen::Vector3d c = k.poses[i].translation(), ax = k.poses[i].linear().col(2);
      kfs.push_back({r2(c.x()), r2(c.y()), r2(c.z()), r3(ax.x()), r3(ax.y()), r3(ax.z())});
    }
  }
  view["keyframes"] = kfs;
  json gpath = json::array();
  if (!gt.poses.empty() && a.scale > 0)
    for (size_t k : thin(gt.poses.size())) {
      const Eigen::Vector3d q = a.R.transpose() * (gt.poses[k].p - a.t) / a.scale;
      gpath.push_back(r2(q.x())), gpath.push_back(r2(q.y())), gpath.push_back(r2(q.z()));
    }
  view["ground_truth"] = gpath;
  return view;
}

// Sample frames the runner drew (masks and features), copied beside the report; their paths from it.
json sampleData(const fs::path& run, const fs::path& samples_out, const std::string& samples_rel) {
  json samples = json::array();
  if (!fs::is_directory(run / "samples")) return samples;
  std::vector<fs::path> pngs;
  for (const auto& e : fs::directory_iterator(run / "samples"))
    if (e.path().extension() == ".png" || e.path().extension() == ".jpg" || e.path().extension() == ".jpeg")
      pngs.push_back(e.path());
  std::sort(pngs.begin(), pngs.end());
  const size_t step = std::max<size_t>(1, (pngs.size() + kMaxSamples - 1) / kMaxSamples);
  if (!pngs.empty()) makeDirectories(samples_out.string());
  for (size_t i = 0; i < pngs.size(); i += step) {
    writeFileAtomic((samples_out / pngs[i].filename()).string(), readFile(pngs[i].string()));
    samples.push_back(samples_rel + "/" + pngs[i].filename().string());
  }
  return samples;
}

}  // namespace

// The report data of one run (folder `run`): see the header for what it holds.
json runData(const fs::path& run, const std::string& label, size_t max_points, const fs::path& samples_out,
             const std::string& samples_rel, std::vector<std::string>* warnings = nullptr) {
  const fs::path summary_path = run / "summary.json";
  json summary;
  try {
    summary = json::parse(readFile(summary_path.string()));
  } catch (const json::exception& e) {
    throwAt(summary_path.string(), std::string("not a run summary: ") + e.what());
  }
  json d = {{"label", label}, {"dir", fs::absolute(run).lexically_normal().string()}};
  const json shown = summaryData(run, summary, warnings);
  if (!shown.is_null()) d["summary"] = shown;
  const std::vector<Pose> est = readEstimate(run);
  const GroundTruth gt = readGroundTruth(summary);
  const Alignment alignment = alignmentOf(summary);
  d["series"] = seriesData(est, gt, alignment);
  d["timing"] = timingData(run / "timing.csv");
  detectionData(run, gt.times, est, d);
  d["view"] = viewData(run, est, gt, alignment, max_points);
  d["samples"] = sampleData(run, samples_out, samples_rel);
  return d;
}

namespace {

std::string scriptJson(const json& j) {
  std::string s = j.dump();
  for (size_t p = 0; (p = s.find("</", p)) != std::string::npos; p += 3) s.replace(p, 2, "<\\/");
  return s;
}

void copyLibraries(const fs::path& lib) {
  const char* env = std::getenv("BESLAM_JS_DIR");
  const fs::path js = env && *env ? fs::path(env) : fs::path("/usr/share/javascript");
  makeDirectories(lib.string());
  const std::vector<std::tuple<std::string, std::string, std::string>> files = {
      {"three/three.min.js", "three.min.js", "libjs-three"},
      {"three/examples/js/controls/OrbitControls.js", "OrbitControls.js", "libjs-three"},
      {"chart.js/chart.min.js", "chart.min.js", "libjs-chart.js"}};
  for (const auto& [from, to, package] : files) {
    const fs::path src = js / from;
    if (!fs::exists(src))
      throwAt(src.string(), "missing: install Debian's " + package + " (scripts/install-deps.sh) or set BESLAM_JS_DIR");
    writeFileAtomic((lib / to).string(), readFile(src.string()));
  }
}

// index.html from the embedded template, the libraries, and one data/run_K.js a run.
void writePage(const fs::path& out, const std::string& title, const json& tables, const std::vector<json>& runs) {
  makeDirectories((out / "data").string());
  copyLibraries(out / "lib");
  json index = {{"title", title}, {"tables", tables}, {"runs", json::array()}};
  for (size_t k = 0; k < runs.size(); ++k) {
    const std::string file = "data/run_" + std::to_string(k) + ".js";
    writeFileAtomic((out / file).string(),
                    "BESLAM_REPORT.addRun(" + std::to_string(k) + ", " + scriptJson(runs[k]) + ");\n");
    index["runs"].push_back({{"label", runs[k]["label"]}, {"file", file}});
  }
  std::string page = kPageTemplate;
  const std::string marker = "/*BESLAM_INDEX*/null";
  const size_t at = page.find(marker);
  if (at == std::string::npos) throw Error("report template: no /*BESLAM_INDEX*/ marker");
  page.replace(at, marker.size(), scriptJson(index));
  std::string esc;
  for (char c : title) esc += c == '<' ? std::string("&lt;") : c == '&' ? std::string("&amp;") : std::string(1, c);
  for (size_t p; (p = page.find("{{TITLE}}")) != std::string::npos;) page.replace(p, 9, esc);
  writeFileAtomic((out / "index.html").string(), page);
}

}  // namespace

std::vector<std::string> writeRunReport(const std::string& run_dir, const std::string& out_dir) {
  const fs::path run(run_dir);
  if (!fs::is_directory(run)) throwAt(run_dir, "no such run folder");
  const fs::path out = out_dir.empty() ? run / "report" : fs::path(out_dir);
  std::string label = fs::absolute(run).lexically_normal().filename().string();
  if (label.empty()) label = fs::absolute(run).lexically_normal().parent_path().filename().string();
  std::vector<std::string> warnings;
  const json d = runData(run, label, 200000, out / "samples" / "0", "samples/0", &warnings);
  writePage(out, "BE-SLAM run " + label, nullptr, {d});
  return warnings;
}

void writeBenchReport(const std::string& bench_dir) {
  const fs::path dir(bench_dir);
  const json bench = json::parse(readFile((dir / "bench.json").string()));
  json tables = nullptr;
  if (fs::exists(dir / "tables.json")) tables = json::parse(readFile((dir / "tables.json").string()));
  const fs::path out = dir / "report";
  std::vector<json> runs;
  for (const auto& c : bench["cells"]) {
    const fs::path run = dir / c["dir"].get<std::string>();
    if (!fs::exists(run / "summary.json")) continue;
    const std::string k = std::to_string(runs.size());
    bool interrupted = false;
    try {
      interrupted = json::parse(readFile((run / "summary.json").string())).value("interrupted", false);
    } catch (const json::exception&) {
      continue;  // a summary being written or broken: not a run to show
    }
    runs.push_back(runData(run,
                           c["pipeline"].get<std::string>() + " / " + c["sequence"].get<std::string>() + " / seed " +
                               std::to_string(c["seed"].get<long>()) + (interrupted ? " (interrupted)" : ""),
                           50000, out / "samples" / k, "samples/" + k));
  }
  writePage(out, "BE-SLAM bench " + bench.value("name", std::string()), tables, runs);
}

int runReportCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  const char* usage =
      "usage: beslam report RUN_DIR [--out DIR]\n"
      "Writes a self-contained HTML report of one run (default RUN_DIR/report/index.html): trajectory against\n"
      "ground truth, APE and scale over time, per-stage timing, detections, sample frames, a 3D map viewer.\n";
  std::string run, out_dir;
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--help" || args[i] == "-h") {
      out << usage;
      return 0;
    } else if (args[i] == "--out" && i + 1 < args.size()) {
      out_dir = args[++i];
    } else if (!args[i].empty() && args[i][0] == '-') {
      err << "beslam report: usage error: unknown option " << args[i] << "\n" << usage;
      return 2;
    } else if (run.empty()) {
      run = args[i];
    } else {
      err << "beslam report: usage error: more than one run folder\n" << usage;
      return 2;
    }
  }
  if (run.empty()) {
    err << "beslam report: usage error: no run folder\n" << usage;
    return 2;
  }
  try {
    for (const std::string& w : writeRunReport(run, out_dir)) err << "beslam report: warning: " << w << "\n";
  } catch (const Error& e) {
    err << "beslam: error: " << e.what() << "\n";
    return 1;
  }
  out << "report: " << (out_dir.empty() ? (fs::path(run) / "report").string() : out_dir) << "/index.html\n";
  return 0;
}

}  // namespace beslam::report
