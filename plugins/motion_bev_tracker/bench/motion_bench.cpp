// motion_bench: the motion checker on real KITTI tracking sequences (PointRCNN detections, ORB-SLAM3 ego
// poses, label_02 truth). Prints per-sequence and overall precision / recall / F1 for 'dynamic', the share
// of moving cars called static, of parked cars called dynamic, and the tracker's time per frame.
//
//   motion_bench [--root DIR] [--sequences 0000,0001,...] [--min-score S] [--max-range M] [--set key=value]...
//                [--trace] [--loo [--grid key=v1,v2,...]...]
//
// --set overrides a tracker parameter by its plugin setting name (gate, pos_sigma, stop_dwell, ...).
//
// --loo: leave-one-sequence-out. Every point of a small grid over the free settings (kLooGrid, or the --grid
// axes given) is evaluated on every sequence once. For each held-out sequence the point is chosen on the
// other sequences' pooled counts (largest F1 among the points with moving called static <= 1 % and parked
// called dynamic <= 3 %, else largest F1; ties go to the earlier point) and the held-out sequence is scored
// with it. Printed: each fold's choice and held-out row, the pooled held-out (cross-validated) figure, the
// point chosen most often (ties: the one chosen on all sequences together), and that point's in-sample
// (fitted) figure on all sequences, labelled as such.
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "kitti_motion_eval.hpp"

namespace {

using beslam::motion::EvalCounts;
using beslam::motion::Params;

// The LOO grid: the settings that no physical argument pins down (docs/motion.md, "Leave-one-sequence-out
// (the figure to quote)"). Axes in order; the first axis varies slowest. 3 x 3 x 3 x 2 x 2 x 3 x 3 = 972 points.
const std::vector<std::pair<std::string, std::vector<std::string>>> kLooGrid = {
    {"ego_speed_noise", {"0", "0.01", "0.02"}},
    {"ego_turn_noise", {"0", "0.05", "0.1"}},
    {"pos_sigma_per_m", {"0.002", "0.005", "0.01"}},
    {"z_dynamic", {"2", "3"}},
    {"z_static", {"2", "3"}},
    {"start_frames", {"1", "2", "3"}},
    {"pull_out_frames", {"1", "2", "3"}},
};

void setParam(beslam::motion::Params& p, const std::string& kv) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos) throw std::invalid_argument("--set expects key=value, got " + kv);
  const std::string k = kv.substr(0, eq), v = kv.substr(eq + 1);
  std::map<std::string, double*> d = {{"gate", &p.gate},
                                      {"gate_per_m", &p.gate_per_m},
                                      {"min_iou", &p.min_iou},
                                      {"accel_sigma", &p.accel_sigma},
                                      {"pos_sigma", &p.pos_sigma},
                                      {"pos_sigma_per_m", &p.pos_sigma_per_m},
                                      {"velocity_sigma", &p.velocity_sigma},
                                      {"init_velocity_sigma", &p.init_velocity_sigma},
                                      {"ego_speed_noise", &p.ego_speed_noise},
                                      {"ego_turn_noise", &p.ego_turn_noise},
                                      {"settling_speed_noise", &p.settling_speed_noise},
                                      {"settling_time", &p.settling_time},
                                      {"max_miss_time", &p.max_miss_time},
                                      {"window_dynamic", &p.window_dynamic},
                                      {"window_static", &p.window_static},
                                      {"dynamic_speed", &p.dynamic_speed},
                                      {"static_speed", &p.static_speed},
                                      {"z_dynamic", &p.z_dynamic},
                                      {"z_static", &p.z_static},
                                      {"max_range", &p.max_range},
                                      {"max_residual", &p.max_residual},
                                      {"displacement_margin", &p.displacement_margin}};
  std::map<std::string, int*> i = {
      {"min_observations", &p.min_observations}, {"start_frames", &p.start_frames},
      {"pull_out_frames", &p.pull_out_frames},   {"stop_dwell", &p.stop_dwell},
      {"anchor_frames", &p.anchor_frames},       {"reference_tracks", &p.reference_tracks}};
  if (k == "association")
    p.association = v;
  else if (d.count(k))
    *d[k] = std::stod(v);
  else if (i.count(k))
    *i[k] = std::stoi(v);
  else
    throw std::invalid_argument("unknown tracker parameter " + k);
}

void row(const std::string& name, const beslam::motion::EvalCounts& c) {
  std::printf(
      "| %-7s | %6lld | %6lld | %6lld | %6lld | %5.3f | %5.3f | %5.3f | %6.2f%% | %6.2f%% | %5.1f%% | %7.4f | %7.4f "
      "|\n",
      name.c_str(), static_cast<long long>(c.frames), static_cast<long long>(c.boxes), static_cast<long long>(c.moving),
      static_cast<long long>(c.parked), c.precision(), c.recall(), c.f1(), 100 * c.movingCalledStatic(),
      100 * c.parkedCalledDynamic(),
      c.labels_scorable ? 100.0 * double(c.labels_matched) / double(c.labels_scorable) : 0.0, c.medianMs(), c.meanMs());
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, sep);)
    if (!item.empty()) out.push_back(item);
  return out;
}

using Grid = std::vector<std::pair<std::string, std::vector<std::string>>>;

// Every combination of the axes, first axis slowest, as key=value lists.
std::vector<std::vector<std::string>> gridPoints(const Grid& grid) {
  std::vector<std::vector<std::string>> points = {{}};
  for (const auto& [key, values] : grid) {
    std::vector<std::vector<std::string>> next;
    for (const auto& p : points)
      for (const auto& v : values) {
        next.push_back(p);
        next.back().push_back(key + "=" + v);
      }
    points = std::move(next);
  }
  return points;
}

std::string joined(const std::vector<std::string>& kv) {
  std::string s;
  for (const auto& x : kv) s += (s.empty() ? "" : " ") + x;
  return s;
}

// The selection rule: feasible points (moving called static <= 1 %, parked called dynamic <= 3 %) beat
// infeasible ones, then larger F1; ties keep the earlier point.
bool better(const EvalCounts& a, const EvalCounts& b) {
  const bool fa = a.movingCalledStatic() <= 0.01 && a.parkedCalledDynamic() <= 0.03;
  const bool fb = b.movingCalledStatic() <= 0.01 && b.parkedCalledDynamic() <= 0.03;
  if (fa != fb) return fa;
  return a.f1() > b.f1() + 1e-12;
}

size_t choose(const std::vector<std::vector<EvalCounts>>& counts, const std::vector<bool>& use) {
  size_t best = 0;
  EvalCounts best_c;
  for (size_t g = 0; g < counts.size(); ++g) {
    EvalCounts c;
    for (size_t s = 0; s < use.size(); ++s)
      if (use[s]) c.add(counts[g][s]);
    if (g == 0 || better(c, best_c)) best = g, best_c = c;
  }
  return best;
}

void header() {
  std::printf(
      "| seq     | frames |  boxes | moving | parked | prec  | rec   | F1    | mov->st | park->dyn | matched | med ms  "
      "| mean ms |\n");
  std::printf(
      "|---------|-------:|-------:|-------:|-------:|------:|------:|------:|--------:|----------:|--------:|--------:"
      "|--------:|\n");
}

}  // namespace

int main(int argc, char** argv) {
  beslam::motion::EvalOptions o;
#ifdef BESLAM_SHARED_DATA
  o.root = std::string(BESLAM_SHARED_DATA) + "/kitti/tracking/training";
#endif
  std::string sequences = "0000,0001,0002,0003,0004,0005,0006,0007,0008,0009,0010";
  bool loo = false;
  Grid grid;
  try {
    for (int a = 1; a < argc; ++a) {
      const std::string arg = argv[a];
      auto next = [&]() -> std::string {
        if (a + 1 >= argc) throw std::invalid_argument(arg + " needs a value");
        return argv[++a];
      };
      if (arg == "--root")
        o.root = next();
      else if (arg == "--sequences")
        sequences = next();
      else if (arg == "--min-score")
        o.min_score = std::stod(next());
      else if (arg == "--max-range")
        o.max_range = std::stod(next());
      else if (arg == "--set")
        setParam(o.params, next());
      else if (arg == "--trace")
        o.trace = &std::cerr;
      else if (arg == "--loo")
        loo = true;
      else if (arg == "--grid") {
        const std::string kv = next();
        const auto eq = kv.find('=');
        if (eq == std::string::npos) throw std::invalid_argument("--grid expects key=v1,v2,..., got " + kv);
        grid.emplace_back(kv.substr(0, eq), split(kv.substr(eq + 1), ','));
        if (grid.back().second.empty()) throw std::invalid_argument("--grid " + kv + " has no values");
      } else if (arg == "-h" || arg == "--help") {
        std::cout << "usage: motion_bench [--root DIR] [--sequences 0000,0001] [--min-score S] [--max-range M] "
                     "[--set key=value]... [--trace] [--loo [--grid key=v1,v2,...]...]\n";
        return 0;
      } else {
        throw std::invalid_argument("unknown argument " + arg);
      }
    }
    const std::string problem = o.params.validate();
    if (!problem.empty()) throw std::invalid_argument(problem);
    std::printf("motion_bench: %s, detections %s (score >= %.2f), poses %s; cars within %.0f m after %d frames\n",
                o.root.c_str(), o.detections.c_str(), o.min_score, o.poses.c_str(), o.max_range, o.warmup);
    if (loo) {
      if (grid.empty()) grid = kLooGrid;
      const std::vector<std::string> seqs = split(sequences, ',');
      if (seqs.size() < 2) throw std::invalid_argument("--loo needs at least two sequences");
      const auto points = gridPoints(grid);
      std::vector<beslam::motion::SequenceDataPtr> data;
      for (const auto& seq : seqs) data.push_back(beslam::motion::loadSequence(o, seq));
      // counts[g][s]: grid point g on sequence s (the tracker is deterministic: each pair is run once).
      std::vector<std::vector<EvalCounts>> counts(points.size());
      std::vector<Params> params(points.size());
      for (size_t g = 0; g < points.size(); ++g) {
        beslam::motion::EvalOptions og = o;
        for (const auto& kv : points[g]) setParam(og.params, kv);
        const std::string problem = og.params.validate();
        if (!problem.empty()) throw std::invalid_argument(joined(points[g]) + ": " + problem);
        params[g] = og.params;
        for (const auto& d : data) {
          counts[g].push_back(beslam::motion::evaluateLoaded(og, *d));
        }
      }
      std::printf("leave-one-sequence-out over %zu sequences, %zu grid points (", seqs.size(), points.size());
      for (size_t a = 0; a < grid.size(); ++a) {
        std::string vs;
        for (const auto& v : grid[a].second) vs += (vs.empty() ? "" : ",") + v;
        std::printf("%s%s {%s}", a ? ", " : "", grid[a].first.c_str(), vs.c_str());
      }
      std::printf("); other settings as given\n\nfolds (point chosen on the other sequences; its training F1):\n");
      EvalCounts held_out;
      std::vector<int> times(points.size(), 0);
      std::vector<std::pair<std::string, EvalCounts>> rows;
      for (size_t s = 0; s < seqs.size(); ++s) {
        std::vector<bool> use(seqs.size(), true);
        use[s] = false;
        const size_t g = choose(counts, use);
        ++times[g];
        EvalCounts train;
        for (size_t t = 0; t < seqs.size(); ++t)
          if (use[t]) train.add(counts[g][t]);
        std::printf("  held out %s: %s (training F1 %.3f, moving->static %.2f%%, parked->dynamic %.2f%%)\n",
                    seqs[s].c_str(), joined(points[g]).c_str(), train.f1(), 100 * train.movingCalledStatic(),
                    100 * train.parkedCalledDynamic());
        held_out.add(counts[g][s]);
        rows.emplace_back(seqs[s], counts[g][s]);
      }
      std::printf("\nheld-out sequences, each with the point chosen without it (CROSS-VALIDATED):\n");
      header();
      for (const auto& [seq, c] : rows) row(seq, c);
      row("LOO", held_out);
      std::printf(
          "LOO pooled: F1 %.3f, moving called static %.2f%%, parked called dynamic %.2f%% "
          "(moving called unknown %lld, parked called unknown %lld)\n",
          held_out.f1(), 100 * held_out.movingCalledStatic(), 100 * held_out.parkedCalledDynamic(),
          static_cast<long long>(held_out.moving_unknown), static_cast<long long>(held_out.parked_unknown));
      const size_t on_all = choose(counts, std::vector<bool>(seqs.size(), true));
      size_t shipped = on_all;
      for (size_t g = 0; g < points.size(); ++g)
        if (times[g] > times[shipped]) shipped = g;
      std::printf("\npoint chosen most often: %s (%d of %zu folds); chosen on all %zu sequences together: %s\n",
                  joined(points[shipped]).c_str(), times[shipped], seqs.size(), seqs.size(),
                  joined(points[on_all]).c_str());
      std::printf("\nthat point on all sequences (FITTED, in-sample: the sequences chose it):\n");
      header();
      EvalCounts fitted;
      for (size_t s = 0; s < seqs.size(); ++s) {
        row(seqs[s], counts[shipped][s]);
        fitted.add(counts[shipped][s]);
      }
      row("fitted", fitted);
      return 0;
    }
    header();
    beslam::motion::EvalCounts all;
    std::stringstream ss(sequences);
    for (std::string seq; std::getline(ss, seq, ',');) {
      const beslam::motion::EvalCounts c = beslam::motion::evaluateSequence(o, seq);
      row(seq, c);
      all.add(c);
    }
    row("overall", all);
    std::printf("moving called unknown: %lld, parked called unknown: %lld\n",
                static_cast<long long>(all.moving_unknown), static_cast<long long>(all.parked_unknown));
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "motion_bench: " << e.what() << "\n";
    return 1;
  }
}
