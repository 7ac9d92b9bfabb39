// motion_bench: the motion checker on real KITTI tracking sequences (PointRCNN detections, ORB-SLAM3 ego
// poses, label_02 truth). Prints per-sequence and overall precision / recall / F1 for 'dynamic', the share
// of moving cars called static, of parked cars called dynamic, and the tracker's time per frame.
//
//   motion_bench [--root DIR] [--sequences 0000,0001,...] [--min-score S] [--max-range M] [--set key=value]...
//
// --set overrides a tracker parameter by its plugin setting name (gate, pos_sigma, stop_dwell, ...).
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <sstream>
#include <string>

#include "kitti_motion_eval.hpp"

namespace {

void setParam(beslam::motion::Params& p, const std::string& kv) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos) throw std::invalid_argument("--set expects key=value, got " + kv);
  const std::string k = kv.substr(0, eq), v = kv.substr(eq + 1);
  std::map<std::string, double*> d = {
      {"gate", &p.gate}, {"gate_per_m", &p.gate_per_m}, {"min_iou", &p.min_iou}, {"accel_sigma", &p.accel_sigma},
      {"pos_sigma", &p.pos_sigma}, {"pos_sigma_per_m", &p.pos_sigma_per_m}, {"velocity_sigma", &p.velocity_sigma}, {"init_velocity_sigma", &p.init_velocity_sigma},
      {"max_miss_time", &p.max_miss_time}, {"window_dynamic", &p.window_dynamic}, {"window_static", &p.window_static},
      {"dynamic_speed", &p.dynamic_speed}, {"dynamic_speed_per_m", &p.dynamic_speed_per_m},
      {"static_speed", &p.static_speed}, {"static_speed_per_m", &p.static_speed_per_m},
      {"z_dynamic", &p.z_dynamic}, {"z_static", &p.z_static}, {"max_range", &p.max_range}, {"max_residual", &p.max_residual}, {"displacement_margin", &p.displacement_margin}};
  std::map<std::string, int*> i = {{"min_observations", &p.min_observations}, {"start_frames", &p.start_frames},
                                   {"stop_dwell", &p.stop_dwell}, {"anchor_frames", &p.anchor_frames}};
  if (k == "association") p.association = v;
  else if (d.count(k)) *d[k] = std::stod(v);
  else if (i.count(k)) *i[k] = std::stoi(v);
  else throw std::invalid_argument("unknown tracker parameter " + k);
}

void row(const std::string& name, const beslam::motion::EvalCounts& c) {
  std::printf("| %-7s | %6lld | %6lld | %6lld | %6lld | %5.3f | %5.3f | %5.3f | %6.2f%% | %6.2f%% | %5.1f%% | %7.4f | %7.4f |\n",
              name.c_str(), static_cast<long long>(c.frames), static_cast<long long>(c.boxes),
              static_cast<long long>(c.moving), static_cast<long long>(c.parked), c.precision(), c.recall(), c.f1(),
              100 * c.movingCalledStatic(), 100 * c.parkedCalledDynamic(),
              c.labels_scorable ? 100.0 * double(c.labels_matched) / double(c.labels_scorable) : 0.0, c.medianMs(),
              c.meanMs());
}

}  // namespace

int main(int argc, char** argv) {
  beslam::motion::EvalOptions o;
#ifdef BESLAM_SHARED_DATA
  o.root = std::string(BESLAM_SHARED_DATA) + "/kitti/tracking/training";
#endif
  std::string sequences = "0000,0001,0002,0003,0004,0005,0006,0007,0008,0009,0010";
  try {
    for (int a = 1; a < argc; ++a) {
      const std::string arg = argv[a];
      auto next = [&]() -> std::string {
        if (a + 1 >= argc) throw std::invalid_argument(arg + " needs a value");
        return argv[++a];
      };
      if (arg == "--root") o.root = next();
      else if (arg == "--sequences") sequences = next();
      else if (arg == "--min-score") o.min_score = std::stod(next());
      else if (arg == "--max-range") o.max_range = std::stod(next());
      else if (arg == "--set") setParam(o.params, next());
      else if (arg == "--trace") o.trace = &std::cerr;
      else if (arg == "-h" || arg == "--help") {
        std::cout << "usage: motion_bench [--root DIR] [--sequences 0000,0001] [--min-score S] [--max-range M] "
                     "[--set key=value]...\n";
        return 0;
      } else {
        throw std::invalid_argument("unknown argument " + arg);
      }
    }
    const std::string problem = o.params.validate();
    if (!problem.empty()) throw std::invalid_argument(problem);
    std::printf("motion_bench: %s, detections %s (score >= %.2f), poses %s; cars within %.0f m after %d frames\n",
                o.root.c_str(), o.detections.c_str(), o.min_score, o.poses.c_str(), o.max_range, o.warmup);
    std::printf("| seq     | frames |  boxes | moving | parked | prec  | rec   | F1    | mov->st | park->dyn | matched | med ms  | mean ms |\n");
    std::printf("|---------|-------:|-------:|-------:|-------:|------:|------:|------:|--------:|----------:|--------:|--------:|--------:|\n");
    beslam::motion::EvalCounts all;
    std::stringstream ss(sequences);
    for (std::string seq; std::getline(ss, seq, ',');) {
      const beslam::motion::EvalCounts c = beslam::motion::evaluateSequence(o, seq);
      row(seq, c);
      all.add(c);
    }
    row("overall", all);
    std::printf("moving called unknown: %lld, parked called unknown: %lld\n", static_cast<long long>(all.moving_unknown),
                static_cast<long long>(all.parked_unknown));
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "motion_bench: " << e.what() << "\n";
    return 1;
  }
}
