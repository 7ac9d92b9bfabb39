// The paper's tables from the finished cells of a bench folder.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
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

// One CSV: the key columns, then a _median, _min and _max column per figure (full precision).
std::string csvOf(const json& rows, const std::vector<std::string>& keys, const std::vector<std::string>& stats) {
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
}

// A finished cell: its summary, timing and the score files of its scoring steps.
struct Run {
  json summary;
  RunTiming timing;
  std::map<std::string, json> scores;  // scoring step -> its eval_<step>.json (absent: not scored)
};

// The finished cells of a bench folder, by (sequence, pipeline), in the order the cells list them.
struct Cells {
  std::vector<std::string> pipelines, sequences;
  std::map<std::pair<std::string, std::string>, std::vector<Run>> runs;
  std::map<std::pair<std::string, std::string>, int> planned;
  int finished = 0;
};

Cells readCells(const std::string& out_dir, const json& bench) {
  Cells cells;
  for (const auto& c : bench["cells"]) {
    const std::string p = c.at("pipeline"), s = c.at("sequence");
    if (std::find(cells.pipelines.begin(), cells.pipelines.end(), p) == cells.pipelines.end())
      cells.pipelines.push_back(p);
    if (std::find(cells.sequences.begin(), cells.sequences.end(), s) == cells.sequences.end())
      cells.sequences.push_back(s);
    cells.planned[{s, p}]++;
    const fs::path dir = fs::path(out_dir) / c.at("dir").get<std::string>();
    if (!cellFinished(dir.string())) continue;
    ++cells.finished;
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
    cells.runs[{s, p}].push_back(std::move(run));
  }
  return cells;
}

// A figure of a run's summary or score file, with its place in the tables.
struct Column {
  std::string key;     // tables.json and CSV name
  std::string header;  // Markdown header
  int digits;          // Markdown decimals
  std::function<double(const json&)> value;
};

double share(const json& j, const char* part, const char* whole) {
  const double w = num(j, {whole});
  return w > 0 ? num(j, {part}) / w : NAN;
}

// Reconstructions of parked cars with a heading error, the share within 10 degrees.
double headingWithin10(const json& j) {
  int parked = 0, within = 0;
  if (j.contains("objects") && j["objects"].is_array())
    for (const auto& x : j["objects"]) {
      const double yaw = num(x, {"yaw_error_deg"});
      if (!x.value("parked", false) || !(yaw >= 0)) continue;
      ++parked, within += yaw <= 10 ? 1 : 0;
    }
  return parked ? double(within) / parked : NAN;
}

// The tables of the scoring steps: one row per (sequence, pipeline) with a scored run.
struct ScoreTable {
  std::string step, key, title;
  std::vector<Column> columns;
};

// A figure read as it is, and one as the share part / whole (NaN when whole is 0).
Column field(std::string key, std::string header, int digits, const char* name) {
  return {std::move(key), std::move(header), digits, [name](const json& j) { return num(j, {name}); }};
}
Column ratio(std::string key, std::string header, const char* part, const char* whole) {
  return {std::move(key), std::move(header), 3, [part, whole](const json& j) { return share(j, part, whole); }};
}

const std::vector<ScoreTable>& scoreTables() {
  static const std::vector<ScoreTable> tables = {
      {"motion",
       "motion",
       "Motion states (scoring step `motion`: `beslam eval-motion`; shares of scored car detections)",
       {field("f1_dynamic", "F1 (dynamic)", 3, "f1_dynamic"),
        ratio("moving_called_static", "moving called static", "moving_static", "moving"),
        ratio("standing_called_dynamic", "standing called dynamic", "standing_dynamic", "standing"),
        ratio("standing_near_called_static", "standing nearby called static", "standing_near_static",
              "standing_near")}},
      {"objects",
       "reconstruction",
       "Reconstructed objects (scoring step `objects`: `beslam eval-objects`)",
       {field("reconstructed", "reconstructed", 0, "reconstructed"),
        ratio("parked_in_view_correct_share", "parked in view, correct", "parked_in_view_correct", "parked_in_view"),
        ratio("false_share", "false", "false", "reconstructed"),
        field("centre_error_m", "centre error m", 3, "median_centre_error_m"),
        field("yaw_error_deg", "yaw error deg", 1, "median_yaw_error_deg"),
        {"heading_within_10_deg_share", "heading within 10 deg", 3, headingWithin10},
        field("chamfer_m", "Chamfer m", 3, "median_chamfer_m"),
        field("shape_chamfer_m", "shape-only Chamfer m", 3, "median_shape_chamfer_m")}},
      {"static_map",
       "static_map",
       "Static map (scoring step `static_map`: `beslam eval-static-map`; voxels)",
       {field("occupied", "occupied", 0, "occupied"),
        field("in_moving_paths", "in moving cars' paths", 0, "in_moving_paths"),
        field("in_parked_cars", "in parked cars", 0, "in_parked_cars"),
        ratio("parked_cars_mapped_share", "parked cars mapped", "parked_cars_near_mapped", "parked_cars_near")}}};
  return tables;
}

// Table I and the objects table: one row per planned (sequence, pipeline), from the summaries.
void summaryRows(const Cells& cells, json& t1, json& objects) {
  for (const auto& s : cells.sequences)
    for (const auto& p : cells.pipelines) {
      if (!cells.planned.count({s, p})) continue;
      const auto it = cells.runs.find({s, p});
      const std::vector<Run> none;
      const auto& rs = it == cells.runs.end() ? none : it->second;
      auto collect = [&](std::initializer_list<const char*> path) {
        std::vector<double> v;
        for (const auto& r : rs) v.push_back(num(r.summary, path));
        return statJson(v);
      };
      json row = {{"sequence", s}, {"pipeline", p}, {"runs", rs.size()}, {"planned", cells.planned.at({s, p})}};
      row["frames"] = collect({"frames"});
      row["tracked"] = collect({"tracked"});
      row["ape_sim3_rmse"] = collect({"ape", "sim3_rmse"});
      row["ape_se3_rmse"] = collect({"ape", "se3_rmse"});
      row["sim3_scale"] = collect({"ape", "sim3_scale"});
      row["rpe_trans_rmse"] = collect({"evaluation", "rpe", "trans", "rmse"});
      row["rpe_rot_rmse"] = collect({"evaluation", "rpe", "rot", "rmse"});
      t1.push_back(row);

      json o = {{"sequence", s}, {"pipeline", p}, {"runs", rs.size()}};
      o["static"] = collect({"detections", "static"});
      o["dynamic"] = collect({"detections", "dynamic"});
      o["unknown"] = collect({"detections", "unknown"});
      o["map_points_static"] = collect({"map_points", "on_static_objects"});
      o["map_points"] = collect({"map_points", "total"});
      o["metric_from_frame"] = collect({"world", "metric_from_frame"});
      int not_metric = 0;
      for (const auto& r : rs) not_metric += std::isfinite(num(r.summary, {"world", "metric_from_frame"})) ? 0 : 1;
      o["not_metric_runs"] = not_metric;
      objects.push_back(o);
    }
}

// A scoring step's rows: medians over the runs of each (sequence, pipeline) that were scored.
json scoreRows(const Cells& cells, const ScoreTable& table) {
  json rows = json::array();
  for (const auto& s : cells.sequences)
    for (const auto& p : cells.pipelines) {
      const auto it = cells.runs.find({s, p});
      if (it == cells.runs.end()) continue;
      std::vector<const json*> scored;
      for (const auto& r : it->second)
        if (r.scores.count(table.step)) scored.push_back(&r.scores.at(table.step));
      if (scored.empty()) continue;
      json row = {{"sequence", s}, {"pipeline", p}, {"runs", scored.size()}};
      for (const Column& c : table.columns) {
        std::vector<double> v;
        for (const json* j : scored) v.push_back(c.value(*j));
        row[c.key] = statJson(v);
      }
      rows.push_back(row);
    }
  return rows;
}

// Table III: per pipeline over all its sequences and seeds.
json timingRows(const Cells& cells) {
  json t3 = json::array();
  for (const auto& p : cells.pipelines) {
    std::vector<double> sem, trk, tot;
    int n = 0;
    for (const auto& s : cells.sequences) {
      const auto it = cells.runs.find({s, p});
      if (it == cells.runs.end()) continue;
      for (const auto& r : it->second) {
        sem.push_back(r.timing.semantic), trk.push_back(r.timing.tracking), tot.push_back(r.timing.total), ++n;
      }
    }
    t3.push_back({{"pipeline", p},
                  {"runs", n},
                  {"semantic_ms", statJson(sem)},
                  {"tracking_ms", statJson(trk)},
                  {"total_ms", statJson(tot)}});
  }
  return t3;
}

std::string markdown(const json& all) {
  std::ostringstream md;
  md << "# " << all["name"].get<std::string>() << ": " << all["finished"] << " of " << all["cells"]
     << " cells finished\n\nMedians over seeds (min–max). APE/RPE: translation RMSE in metres (RPE rot in degrees), "
        "from each run's summary.json; RPE under the pipeline's own alignment. No range: all runs agree.\n\n"
     << "## Table I: trajectory error\n\n"
     << "| sequence | pipeline | runs | tracked | APE Sim(3) m | APE SE(3) m | Sim(3) scale | RPE trans m | RPE rot "
        "deg |\n"
     << "|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : all["table1"])
    md << "| " << r["sequence"].get<std::string>() << " | " << r["pipeline"].get<std::string>() << " | " << r["runs"]
       << "/" << r["planned"] << " | " << fmt(r["tracked"], 0) << " of " << fmt(r["frames"], 0) << " | "
       << fmt(r["ape_sim3_rmse"], 3) << " | " << fmt(r["ape_se3_rmse"], 3) << " | " << fmt(r["sim3_scale"], 3) << " | "
       << fmt(r["rpe_trans_rmse"], 4) << " | " << fmt(r["rpe_rot_rmse"], 3) << " |\n";
  md << "\n## Table III: run time (ms per frame; per-run medians over frames, then medians over runs)\n\n"
     << "| pipeline | runs | semantic ms (detector + motion checker + mask) | tracking ms (backend) | total ms |\n"
     << "|---|---|---|---|---|\n";
  for (const auto& r : all["table3"])
    md << "| " << r["pipeline"].get<std::string>() << " | " << r["runs"] << " | " << fmt(r["semantic_ms"], 2) << " | "
       << fmt(r["tracking_ms"], 2) << " | " << fmt(r["total_ms"], 2) << " |\n";
  md << "\n## Objects\n\n"
     << "| sequence | pipeline | runs | detections static | dynamic | unknown | map points on static objects | "
        "map points | metric from frame | runs not metric |\n"
     << "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : all["objects"])
    md << "| " << r["sequence"].get<std::string>() << " | " << r["pipeline"].get<std::string>() << " | " << r["runs"]
       << " | " << fmt(r["static"], 0) << " | " << fmt(r["dynamic"], 0) << " | " << fmt(r["unknown"], 0) << " | "
       << fmt(r["map_points_static"], 0) << " | " << fmt(r["map_points"], 0) << " | " << fmt(r["metric_from_frame"], 0)
       << " | " << r["not_metric_runs"] << " |\n";
  for (const ScoreTable& t : scoreTables()) {
    const json& rows = all[t.key];
    if (rows.empty()) continue;
    md << "\n## " << t.title << "\n\n| sequence | pipeline | runs |";
    for (const Column& c : t.columns) md << " " << c.header << " |";
    md << "\n|---|---|---|";
    for (size_t i = 0; i < t.columns.size(); ++i) md << "---|";
    md << "\n";
    for (const auto& r : rows) {
      md << "| " << r["sequence"].get<std::string>() << " | " << r["pipeline"].get<std::string>() << " | " << r["runs"]
         << " |";
      for (const Column& c : t.columns) md << " " << fmt(r[c.key], c.digits) << " |";
      md << "\n";
    }
  }
  return md.str();
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

  const Cells cells = readCells(out_dir, bench);
  json t1 = json::array(), objects = json::array();
  summaryRows(cells, t1, objects);
  json all = {{"name", bench.value("name", "")}, {"cells", bench["cells"].size()},
              {"finished", cells.finished},      {"pipelines", cells.pipelines},
              {"sequences", cells.sequences},    {"table1", t1},
              {"table3", timingRows(cells)},     {"objects", objects}};
  for (const ScoreTable& t : scoreTables()) all[t.key] = scoreRows(cells, t);

  const fs::path out(out_dir);
  writeFileAtomic((out / "table1.csv").string(), csvOf(t1, {"sequence", "pipeline", "runs"},
                                                       {"tracked", "frames", "ape_sim3_rmse", "ape_se3_rmse",
                                                        "sim3_scale", "rpe_trans_rmse", "rpe_rot_rmse"}));
  writeFileAtomic((out / "table3.csv").string(),
                  csvOf(all["table3"], {"pipeline", "runs"}, {"semantic_ms", "tracking_ms", "total_ms"}));
  writeFileAtomic((out / "objects.csv").string(),
                  csvOf(objects, {"sequence", "pipeline", "runs", "not_metric_runs"},
                        {"static", "dynamic", "unknown", "map_points_static", "map_points", "metric_from_frame"}));
  for (const ScoreTable& t : scoreTables()) {
    if (all[t.key].empty()) continue;
    std::vector<std::string> keys;
    for (const Column& c : t.columns) keys.push_back(c.key);
    writeFileAtomic((out / (t.key + ".csv")).string(), csvOf(all[t.key], {"sequence", "pipeline", "runs"}, keys));
  }
  writeFileAtomic((out / "tables.md").string(), markdown(all));
  writeFileAtomic((out / "tables.json").string(), all.dump(1) + "\n");
  return all;
}

}  // namespace beslam::bench
