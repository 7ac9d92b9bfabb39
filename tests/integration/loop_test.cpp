// A full synthetic loop closure, end to end: `beslam run` with backend_orb on a small rendered town (one
// 50 x 50 m block driven round once and some 80 frames more, parked cars only) closes the loop when the
// camera comes back to its start: at the frame the ground truth says the revisit starts (within 20
// frames, as issue 18 asks), with a keyframe of the same place, and ends nearer the truth than the same
// run with loop closing off. Rendered once into the build's synth-cache (300 frames), seeded, in the
// deterministic mode (mapping inline): the same outcome on every run, whatever the machine's load.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <vector>

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The text after the first "key": in a JSON text, up to the next comma or brace.
std::string jsonValue(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\":");
  if (at == std::string::npos) return {};
  const size_t from = at + key.size() + 3;
  return json.substr(from, json.find_first_of(",}\n", from) - from);
}

struct Pose {
  double c[3];  // camera centre
  double z[3];  // optical axis
};

// Camera centres and optical axes of a KITTI pose file (one 3x4 row per frame).
std::vector<Pose> readKitti(const fs::path& path) {
  std::vector<Pose> out;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    std::istringstream ss(line);
    double v[12];
    int n = 0;
    while (n < 12 && ss >> v[n]) ++n;
    if (n == 12) out.push_back({{v[3], v[7], v[11]}, {v[2], v[6], v[10]}});
  }
  return out;
}

double dist(const double* a, const double* b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// docs/place-recognition.md's definition: the first frame whose camera is within 3 m of a frame at least
// 100 m of driving earlier, looking the same way (within 30 degrees); -1 when there is none.
int revisitStart(const std::vector<Pose>& gt, int* seen) {
  std::vector<double> s(gt.size(), 0.0);
  for (size_t i = 1; i < gt.size(); ++i) s[i] = s[i - 1] + dist(gt[i].c, gt[i - 1].c);
  for (size_t i = 0; i < gt.size(); ++i)
    for (size_t j = 0; j < i && s[i] - s[j] >= 100.0; ++j) {
      const double cosine = gt[i].z[0] * gt[j].z[0] + gt[i].z[1] * gt[j].z[1] + gt[i].z[2] * gt[j].z[2];
      if (dist(gt[i].c, gt[j].c) < 3.0 && cosine > std::cos(30.0 * M_PI / 180.0)) {
        *seen = static_cast<int>(j);
        return static_cast<int>(i);
      }
    }
  return -1;
}

TEST(LoopClosure, ASmallRenderedLoopIsClosedWhereItIsRevisited) {
  const fs::path dir = fs::temp_directory_path() / ("beslam_loop_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  // One block of the smallest town beslam synth makes; the demo's camera; parked cars only.
  std::ofstream(dir / "loop_town.yaml")
      << "seed: 3\nsequence: \"00\"\nframes: 300\nrate_hz: 10\n"
      << "camera: {width: 1241, height: 376, fx: 718.856, fy: 718.856, cx: 607.1928, cy: 185.2157, "
         "mount_height: 1.65, grey: true, colour: false}\n"
      << "ego: {speed_kmh: 33}\n"
      << "world: {type: urban, blocks_x: 3, blocks_y: 3, block_x: 50, block_y: 50, lanes_per_direction: 1, "
         "parking_lanes: true}\n"
      << "objects: {parked: 20, driving: 0, stop_and_go: 0, pedestrians: 0}\n"
      << "lidar: {enabled: false}\n";
  std::ofstream(dir / "pipeline.yaml") << "dataset: {type: synth, root: " << BESLAM_BINARY_DIR
                                       << "/synth-cache, sequence: " << (dir / "loop_town.yaml").string() << "}\n"
                                       << "backend: {plugin: backend_orb, features: 3000, seed: 1}\n";
  const std::string cmd = "BESLAM_ORB_DEBUG=1 " + std::string(BESLAM_BINARY_DIR) + "/bin/beslam run " +
                          (dir / "pipeline.yaml").string() + " --out " + (dir / "out").string() + " > " +
                          (dir / "stdout.txt").string() + " 2> " + (dir / "stderr.txt").string() + " < /dev/null";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(dir / "stdout.txt");
  const std::string summary = slurp(dir / "out/summary.json");
  EXPECT_EQ(jsonValue(summary, "tracked"), " 300") << summary;

  // The ground truth of the rendered sequence: where the revisit starts.
  std::string seq_dir = jsonValue(summary, "dataset_path");
  ASSERT_GE(seq_dir.size(), 2u) << summary;
  seq_dir = seq_dir.substr(seq_dir.find('"') + 1);
  seq_dir = seq_dir.substr(0, seq_dir.find('"'));
  const std::vector<Pose> gt = readKitti(fs::path(seq_dir).parent_path().parent_path() / "poses/00.txt");
  ASSERT_EQ(gt.size(), 300u);
  int seen = -1;
  const int revisit = revisitStart(gt, &seen);
  ASSERT_GT(revisit, 150) << "the rendered drive does not come back to its start";

  // The closures backend_orb reports (BESLAM_ORB_DEBUG): the first joins the revisit to the start.
  const std::regex closed(R"(frame (\d+): loop closed, keyframe of frame (\d+) with frame (\d+))");
  std::vector<std::pair<int, int>> closures;  // keyframe's frame, loop keyframe's frame
  std::ifstream log(dir / "stderr.txt");
  for (std::string line; std::getline(log, line);) {
    std::smatch m;
    if (line.find("loop closed") != std::string::npos && std::regex_search(line, m, closed))
      closures.emplace_back(std::stoi(m[2]), std::stoi(m[3]));
  }
  ASSERT_FALSE(closures.empty()) << "no loop closed; revisit from frame " << revisit;
  EXPECT_EQ(jsonValue(summary, "loop_closures"), " " + std::to_string(closures.size()) + ".0") << summary;
  // summary.json and the closing lines name each closure's frame (at or after its keyframe's) and correction.
  const nlohmann::json frames = nlohmann::json::parse(summary)["loop_closure_frames"];
  ASSERT_EQ(frames.size(), closures.size()) << summary;
  for (size_t k = 0; k < closures.size(); ++k) {
    EXPECT_GE(frames[k]["frame"].get<int>(), closures[k].first) << summary;
    EXPECT_GT(frames[k]["correction"].get<double>(), 0.0) << summary;
  }
  // Each correction of a metric map is also told to the host as a move of the world (ABI 1.7), which the
  // host hands to the motion checker; corrections of a map in an unknown unit are not (no checker has poses).
  const nlohmann::json world = nlohmann::json::parse(summary)["world"];
  if (world["metric"].get<bool>())
    EXPECT_GE(world["moves"].get<int>(), static_cast<int>(closures.size())) << summary;
  else
    EXPECT_EQ(world["moves"].get<int>(), 0) << summary;
  const std::string printed = "loop closures: " + std::to_string(closures.size()) + " (frame " +
                              std::to_string(frames[0]["frame"].get<int>()) + " corrected by ";
  EXPECT_NE(slurp(dir / "stdout.txt").find(printed), std::string::npos) << slurp(dir / "stdout.txt");
  // Loop closing's cost per keyframe is in timing.csv: the query, the candidates' checks, the correction.
  const std::string timing = slurp(dir / "out/timing.csv");
  for (const char* column : {"backend.loop_query_ms", "backend.loop_check_ms", "backend.loop_correct_ms"})
    EXPECT_NE(timing.substr(0, timing.find('\n')).find(column), std::string::npos) << column;
  const auto [at, with] = closures.front();
  EXPECT_GE(at, revisit - 10) << "closed before the revisit";
  EXPECT_LE(at, revisit + 20) << "closed more than 20 frames after the revisit started at frame " << revisit;
  EXPECT_LT(dist(gt[static_cast<size_t>(at)].c, gt[static_cast<size_t>(with)].c), 10.0)
      << "frames " << at << " and " << with << " are not the same place";

  // The closure makes the trajectory better: the same run with loop closing off ends further from the truth
  // (Sim(3) APE 0.032 m against 0.074 m when this was written; the lap is short and drifts little).
  const std::string off_cmd = std::string(BESLAM_BINARY_DIR) + "/bin/beslam run " + (dir / "pipeline.yaml").string() +
                              " --set backend.loop_closure=false --out " + (dir / "off").string() +
                              " > /dev/null 2>&1 < /dev/null";
  const int off_status = std::system(off_cmd.c_str());
  ASSERT_TRUE(WIFEXITED(off_status) && WEXITSTATUS(off_status) == 0);
  const std::string off = slurp(dir / "off/summary.json");
  EXPECT_EQ(jsonValue(off, "loop_closures"), " 0.0") << off;
  EXPECT_LT(std::stod(jsonValue(summary, "sim3_rmse")), std::stod(jsonValue(off, "sim3_rmse")))
      << "loop closed: " << summary << "\nloop closing off: " << off;
  fs::remove_all(dir);
}

}  // namespace
