// The paper's tables from the finished cells of a bench folder.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "beslam/bench/bench.hpp"
#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace beslam::bench {

std::optional<Stat> stat(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return std::nullopt;
  std::sort(v.begin(), v.end());
  Stat s;
  s.n = static_cast<int>(v.size());
  s.min = v.front();
  s.max = v.back();
  const size_t h = v.size() / 2;
  s.median = v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
  return s;
}

namespace {

// Per-frame medians of a run's timing.csv: semantic (detector + motion checker + mask generator),
// tracking (backend), total. NaN where the run has no such stage.
struct RunTiming {
  double semantic = NAN, tracking = NAN, total = NAN;
};

RunTiming readTiming(const fs::path& csv) {
  RunTiming t;
  std::ifstream in(csv);
  if (!in) return t;
  std::string header;
  if (!std::getline(in, header)) return t;
  std::vector<std::string> cols;
  {
    std::stringstream ss(header);
    for (std::string c; std::getline(ss, c, ',');) cols.push_back(c);
  }
  std::vector<int> semantic_cols;
  int backend = -1, total = -1;
  for (int i = 0; i < static_cast<int>(cols.size()); ++i) {
    if (cols[i] == "detector_ms" || cols[i] == "motion_checker_ms" || cols[i] == "mask_generator_ms")
      semantic_cols.push_back(i);
    if (cols[i] == "backend_ms") backend = i;
    if (cols[i] == "total_ms") total = i;
  }
  std::vector<double> sem, trk, tot;
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) f.push_back(c);
    auto num = [&](int i) { return i >= 0 && i < static_cast<int>(f.size()) && !f[i].empty() ? std::stod(f[i]) : NAN; };
    if (!semantic_cols.empty()) {
      double s = 0;
      bool any = false;
      for (int i : semantic_cols)
        if (std::isfinite(num(i))) s += num(i), any = true;
      if (any) sem.push_back(s);
    }
    if (std::isfinite(num(backend))) trk.push_back(num(backend));
    if (std::isfinite(num(total))) tot.push_back(num(total));
  }
  auto med = [](const std::vector<double>& v) {
    const auto s = stat(v);
    return s ? s->median : NAN;
  };
  t.semantic = med(sem);
  t.tracking = med(trk);
  t.total = med(tot);
  return t;
}

double num(const json& j, std::initializer_list<const char*> path) {
  const json* p = &j;
  for (const char* k : path) {
    if (!p->is_object() || !p->contains(k)) return NAN;
    p = &(*p)[k];
  }
  return p->is_number() ? p->get<double>() : NAN;
}

json statJson(const std::vector<double>& v) {
  const auto s = stat(v);
  if (!s) return nullptr;
  return {{"median", s->median}, {"min", s->min}, {"max", s->max}, {"n", s->n}};
}

std::string fmt(const json& s, int digits) {
  if (s.is_null()) return "-";
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << s["median"].get<double>();
  if (s["n"].get<int>() > 1 && s["min"] != s["max"])
    o << " (" << s["min"].get<double>() << "–" << s["max"].get<double>() << ")";
  return o.str();
}

std::string csvNum(const json& s, const char* k) {
  if (s.is_null()) return "";
  return json(s[k].get<double>()).dump();  // the shortest text that reads back to the same double
}

}  // namespace

json writeTables(const std::string& out_dir) {
  const fs::path bench_json = fs::path(out_dir) / "bench.json";
  json bench;
  try {
    bench = json::parse(readFile(bench_json.string()));
  } catch (const json::exception& e) {
    throwAt(bench_json.string(), std::string("not a bench description: ") + e.what());
  }
  if (!bench.contains("cells") || !bench["cells"].is_array())
    throwAt(bench_json.string(), "not a bench description: no 'cells' list");

  struct Run {
    json summary;
    RunTiming timing;
    std::map<std::string, json> scores;  // scoring step -> its eval_<step>.json (absent: not scored)
  };
  std::vector<std::string> pipelines, sequences;
  std::map<std::pair<std::string, std::string>, std::vector<Run>> runs;  // (sequence, pipeline)
  std::map<std::pair<std::string, std::string>, int> planned;
  int finished = 0;
  for (const auto& c : bench["cells"]) {
    const std::string p = c.at("pipeline"), s = c.at("sequence");
    if (std::find(pipelines.begin(), pipelines.end(), p) == pipelines.end()) pipelines.push_back(p);
    if (std::find(sequences.begin(), sequences.end(), s) == sequences.end()) sequences.push_back(s);
    planned[{s, p}]++;
    const fs::path dir = fs::path(out_dir) / c.at("dir").get<std::string>();
    if (!cellFinished(dir.string())) continue;
    ++finished;
    Run run{json::parse(readFile((dir / "summary.json").string())), readTiming(dir / "timing.csv"), {}};
    for (const auto& step : kScoreSteps) {
      const fs::path score = dir / ("eval_" + step + ".json");
      if (!c.contains("score") || !fs::exists(score)) continue;
      try {
        run.scores[step] = json::parse(readFile(score.string()));
      } catch (const json::exception& e) {
        throwAt(score.string(), std::string("not a score file: ") + e.what());
      }
    }
    runs[{s, p}].push_back(std::move(run));
  }

  json t1 = json::array(), t3 = json::array(), objects = json::array();
  json motion = json::array(), reconstruction = json::array(), static_map = json::array();
  for (const auto& s : sequences)
    for (const auto& p : pipelines) {
      if (!planned.count({s, p})) continue;
      const auto& rs = runs[{s, p}];
      auto collect = [&](auto f) {
        std::vector<double> v;
        for (const auto& r : rs) v.push_back(f(r.summary));
        return statJson(v);
      };
      json row = {{"sequence", s}, {"pipeline", p}, {"runs", rs.size()}, {"planned", planned[{s, p}]}};
      row["frames"] = collect([](const json& j) { return num(j, {"frames"}); });
      row["tracked"] = collect([](const json& j) { return num(j, {"tracked"}); });
      row["ape_sim3_rmse"] = collect([](const json& j) { return num(j, {"ape", "sim3_rmse"}); });
      row["ape_se3_rmse"] = collect([](const json& j) { return num(j, {"ape", "se3_rmse"}); });
      row["sim3_scale"] = collect([](const json& j) { return num(j, {"ape", "sim3_scale"}); });
      row["rpe_trans_rmse"] = collect([](const json& j) { return num(j, {"evaluation", "rpe", "trans", "rmse"}); });
      row["rpe_rot_rmse"] = collect([](const json& j) { return num(j, {"evaluation", "rpe", "rot", "rmse"}); });
      t1.push_back(row);

      json o = {{"sequence", s}, {"pipeline", p}, {"runs", rs.size()}};
      o["static"] = collect([](const json& j) { return num(j, {"detections", "static"}); });
      o["dynamic"] = collect([](const json& j) { return num(j, {"detections", "dynamic"}); });
      o["unknown"] = collect([](const json& j) { return num(j, {"detections", "unknown"}); });
      o["map_points_static"] = collect([](const json& j) { return num(j, {"map_points", "on_static_objects"}); });
      o["map_points"] = collect([](const json& j) { return num(j, {"map_points", "total"}); });
      o["metric_from_frame"] = collect([](const json& j) { return num(j, {"world", "metric_from_frame"}); });
      int not_metric = 0;
      for (const auto& r : rs) not_metric += std::isfinite(num(r.summary, {"world", "metric_from_frame"})) ? 0 : 1;
      o["not_metric_runs"] = not_metric;
      objects.push_back(o);

      // The scoring steps' results: a row where at least one run of the cell was scored.
      auto scored = [&](const std::string& step, auto f) {
        std::vector<double> v;
        for (const auto& r : rs)
          if (r.scores.count(step)) v.push_back(f(r.scores.at(step)));
        return statJson(v);
      };
      auto share = [](const json& j, const char* part, const char* whole) {
        const double w = num(j, {whole});
        return w > 0 ? num(j, {part}) / w : NAN;
      };
      auto scoredRuns = [&](const std::string& step) {
        int n = 0;
        for (const auto& r : rs) n += r.scores.count(step) ? 1 : 0;
        return n;
      };
      if (scoredRuns("motion") > 0) {
        json m = {{"sequence", s}, {"pipeline", p}, {"runs", scoredRuns("motion")}};
        m["f1_dynamic"] = scored("motion", [](const json& j) { return num(j, {"f1_dynamic"}); });
        m["moving_called_static"] =
            scored("motion", [&](const json& j) { return share(j, "moving_static", "moving"); });
        m["standing_called_dynamic"] =
            scored("motion", [&](const json& j) { return share(j, "standing_dynamic", "standing"); });
        m["standing_near_called_static"] =
            scored("motion", [&](const json& j) { return share(j, "standing_near_static", "standing_near"); });
        motion.push_back(m);
      }
      if (scoredRuns("objects") > 0) {
        json o2 = {{"sequence", s}, {"pipeline", p}, {"runs", scoredRuns("objects")}};
        o2["reconstructed"] = scored("objects", [](const json& j) { return num(j, {"reconstructed"}); });
        o2["parked_in_view_correct_share"] =
            scored("objects", [&](const json& j) { return share(j, "parked_in_view_correct", "parked_in_view"); });
        o2["false_share"] = scored("objects", [&](const json& j) { return share(j, "false", "reconstructed"); });
        o2["centre_error_m"] = scored("objects", [](const json& j) { return num(j, {"median_centre_error_m"}); });
        o2["yaw_error_deg"] = scored("objects", [](const json& j) { return num(j, {"median_yaw_error_deg"}); });
        o2["heading_within_10_deg_share"] = scored("objects", [](const json& j) {
          int parked = 0, within = 0;  // reconstructions of parked cars with a heading error
          if (j.contains("objects") && j["objects"].is_array())
            for (const auto& x : j["objects"]) {
              const double yaw = num(x, {"yaw_error_deg"});
              if (!x.value("parked", false) || !(yaw >= 0)) continue;
              ++parked, within += yaw <= 10 ? 1 : 0;
            }
          return parked ? double(within) / parked : NAN;
        });
        o2["chamfer_m"] = scored("objects", [](const json& j) { return num(j, {"median_chamfer_m"}); });
        o2["shape_chamfer_m"] = scored("objects", [](const json& j) { return num(j, {"median_shape_chamfer_m"}); });
        reconstruction.push_back(o2);
      }
      if (scoredRuns("static_map") > 0) {
        json m = {{"sequence", s}, {"pipeline", p}, {"runs", scoredRuns("static_map")}};
        m["occupied"] = scored("static_map", [](const json& j) { return num(j, {"occupied"}); });
        m["in_moving_paths"] = scored("static_map", [](const json& j) { return num(j, {"in_moving_paths"}); });
        m["in_parked_cars"] = scored("static_map", [](const json& j) { return num(j, {"in_parked_cars"}); });
        m["parked_cars_mapped_share"] = scored(
            "static_map", [&](const json& j) { return share(j, "parked_cars_near_mapped", "parked_cars_near"); });
        static_map.push_back(m);
      }
    }
  for (const auto& p : pipelines) {
    std::vector<double> sem, trk, tot;
    int n = 0;
    for (const auto& s : sequences)
      for (const auto& r : runs[{s, p}]) {
        sem.push_back(r.timing.semantic), trk.push_back(r.timing.tracking), tot.push_back(r.timing.total), ++n;
      }
    t3.push_back({{"pipeline", p},
                  {"runs", n},
                  {"semantic_ms", statJson(sem)},
                  {"tracking_ms", statJson(trk)},
                  {"total_ms", statJson(tot)}});
  }

  json all = {{"name", bench.value("name", "")},
              {"cells", bench["cells"].size()},
              {"finished", finished},
              {"pipelines", pipelines},
              {"sequences", sequences},
              {"table1", t1},
              {"table3", t3},
              {"objects", objects},
              {"motion", motion},
              {"reconstruction", reconstruction},
              {"static_map", static_map}};

  // Markdown
  std::ostringstream md;
  md << "# " << all["name"].get<std::string>() << ": " << finished << " of " << bench["cells"].size()
     << " cells finished\n\nMedians over seeds (min–max). APE/RPE: translation RMSE in metres (RPE rot in degrees), "
        "from each run's summary.json; RPE under the pipeline's own alignment. No range: all runs agree.\n\n"
     << "## Table I: trajectory error\n\n"
     << "| sequence | pipeline | runs | tracked | APE Sim(3) m | APE SE(3) m | Sim(3) scale | RPE trans m | RPE rot "
        "deg |\n"
     << "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : t1)
    md << "| " << r["sequence"].get<std::string>() << " | " << r["pipeline"].get<std::string>() << " | " << r["runs"]
       << "/" << r["planned"] << " | " << fmt(r["tracked"], 0) << " of " << fmt(r["frames"], 0) << " | "
       << fmt(r["ape_sim3_rmse"], 3) << " | " << fmt(r["ape_se3_rmse"], 3) << " | " << fmt(r["sim3_scale"], 3) << " | "
       << fmt(r["rpe_trans_rmse"], 4) << " | " << fmt(r["rpe_rot_rmse"], 3) << " |\n";
  md << "\n## Table III: run time (ms per frame; per-run medians over frames, then medians over runs)\n\n"
     << "| pipeline | runs | semantic ms (detector + motion checker + mask) | tracking ms (backend) | total ms |\n"
     << "|---|---|---|---|---|\n";
  for (const auto& r : t3)
    md << "| " << r["pipeline"].get<std::string>() << " | " << r["runs"] << " | " << fmt(r["semantic_ms"], 2) << " | "
       << fmt(r["tracking_ms"], 2) << " | " << fmt(r["total_ms"], 2) << " |\n";
  md << "\n## Objects\n\n"
     << "| sequence | pipeline | runs | detections static | dynamic | unknown | map points on static objects | "
        "map points | metric from frame | runs not metric |\n"
     << "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : objects)
    md << "| " << r["sequence"].get<std::string>() << " | " << r["pipeline"].get<std::string>() << " | " << r["runs"]
       << " | " << fmt(r["static"], 0) << " | " << fmt(r["dynamic"], 0) << " | " << fmt(r["unknown"], 0) << " | "
       << fmt(r["map_points_static"], 0) << " | " << fmt(r["map_points"], 0) << " | " << fmt(r["metric_from_frame"], 0)
       << " | " << r["not_metric_runs"] << " |\n";

  if (!motion.empty()) {
    md << "\n## Motion states (scoring step `motion`: `beslam eval-motion`; shares of scored car detections)\n\n"
       << "| sequence | pipeline | runs | F1 (dynamic) | moving called static | standing called dynamic | "
          "standing nearby called static |\n"
       << "|---|---|---|---|---|---|---|\n";
    for (const auto& r : motion)
      md << "| " << r["sequence"].get<std::string>() << " | " << r["pipeline"].get<std::string>() << " | " << r["runs"]
         << " | " << fmt(r["f1_dynamic"], 3) << " | " << fmt(r["moving_called_static"], 3) << " | "
         << fmt(r["standing_called_dynamic"], 3) << " | " << fmt(r["standing_near_called_static"], 3) << " |\n";
  }
  if (!reconstruction.empty()) {
    md << "\n## Reconstructed objects (scoring step `objects`: `beslam eval-objects`)\n\n"
       << "| sequence | pipeline | runs | reconstructed | parked in view, correct | false | centre error m | yaw "
          "error deg | heading within 10 deg | Chamfer m | shape-only Chamfer m |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : reconstruction)
      md << "| " << r["sequence"].get<std::string>() << " | " << r["pipeline"].get<std::string>() << " | " << r["runs"]
         << " | " << fmt(r["reconstructed"], 0) << " | " << fmt(r["parked_in_view_correct_share"], 3) << " | "
         << fmt(r["false_share"], 3) << " | " << fmt(r["centre_error_m"], 3) << " | " << fmt(r["yaw_error_deg"], 1)
         << " | " << fmt(r["heading_within_10_deg_share"], 3) << " | " << fmt(r["chamfer_m"], 3) << " | "
         << fmt(r["shape_chamfer_m"], 3) << " |\n";
  }
  if (!static_map.empty()) {
    md << "\n## Static map (scoring step `static_map`: `beslam eval-static-map`; voxels)\n\n"
       << "| sequence | pipeline | runs | occupied | in moving cars' paths | in parked cars | parked cars mapped |\n"
       << "|---|---|---|---|---|---|---|\n";
    for (const auto& r : static_map)
      md << "| " << r["sequence"].get<std::string>() << " | " << r["pipeline"].get<std::string>() << " | " << r["runs"]
         << " | " << fmt(r["occupied"], 0) << " | " << fmt(r["in_moving_paths"], 0) << " | "
         << fmt(r["in_parked_cars"], 0) << " | " << fmt(r["parked_cars_mapped_share"], 3) << " |\n";
  }

  // CSV: one column per median / min / max, full precision.
  auto csv = [&](const json& rows, const std::vector<std::string>& keys, const std::vector<std::string>& stats) {
    std::ostringstream o;
    for (size_t i = 0; i < keys.size(); ++i) o << (i ? "," : "") << keys[i];
    for (const auto& k : stats) o << "," << k << "_median," << k << "_min," << k << "_max";
    o << "\n";
    for (const auto& r : rows) {
      for (size_t i = 0; i < keys.size(); ++i) {
        o << (i ? "," : "");
        if (r[keys[i]].is_string())
          o << r[keys[i]].get<std::string>();
        else
          o << r[keys[i]].dump();
      }
      for (const auto& k : stats)
        o << "," << csvNum(r[k], "median") << "," << csvNum(r[k], "min") << "," << csvNum(r[k], "max");
      o << "\n";
    }
    return o.str();
  };
  const fs::path out(out_dir);
  writeFileAtomic((out / "table1.csv").string(), csv(t1, {"sequence", "pipeline", "runs"},
                                                     {"tracked", "frames", "ape_sim3_rmse", "ape_se3_rmse",
                                                      "sim3_scale", "rpe_trans_rmse", "rpe_rot_rmse"}));
  writeFileAtomic((out / "table3.csv").string(),
                  csv(t3, {"pipeline", "runs"}, {"semantic_ms", "tracking_ms", "total_ms"}));
  writeFileAtomic((out / "objects.csv").string(),
                  csv(objects, {"sequence", "pipeline", "runs", "not_metric_runs"},
                      {"static", "dynamic", "unknown", "map_points_static", "map_points", "metric_from_frame"}));
  if (!motion.empty())
    writeFileAtomic((out / "motion.csv").string(), csv(motion, {"sequence", "pipeline", "runs"},
                                                       {"f1_dynamic", "moving_called_static", "standing_called_dynamic",
                                                        "standing_near_called_static"}));
  if (!reconstruction.empty())
    writeFileAtomic((out / "reconstruction.csv").string(),
                    csv(reconstruction, {"sequence", "pipeline", "runs"},
                        {"reconstructed", "parked_in_view_correct_share", "false_share", "centre_error_m",
                         "yaw_error_deg", "heading_within_10_deg_share", "chamfer_m", "shape_chamfer_m"}));
  if (!static_map.empty())
    writeFileAtomic((out / "static_map.csv").string(),
                    csv(static_map, {"sequence", "pipeline", "runs"},
                        {"occupied", "in_moving_paths", "in_parked_cars", "parked_cars_mapped_share"}));
  writeFileAtomic((out / "tables.md").string(), md.str());
  writeFileAtomic((out / "tables.json").string(), all.dump(1) + "\n");
  return all;
}

}  // namespace beslam::bench
