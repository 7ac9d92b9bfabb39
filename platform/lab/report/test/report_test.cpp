// beslam report: the figures of a hand-made run (known APE, scale, boxes) in the page's data, errors that
// name the file, and the page as a person sees it: headless Chromium loads a real run's report with no
// JavaScript error, and its screenshot shows the plots' colours and a drawn 3D canvas.
#include "beslam/report/report.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/test/temp_dir.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using beslam::test::readText;

fs::path tempDir(const std::string& name) {
  const fs::path d = fs::path(BESLAM_BINARY_DIR) / "test-report" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

int shell(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// 50 frames straight ahead at 1 m a frame; the estimate is at half scale, shifted, and 0.3 m off
// sideways from frame 25 on; the summary's alignment (scale 2, x - 2) maps it back onto the truth.
fs::path makeRun(const fs::path& dir) {
  const fs::path seq = dir / "data" / "sequences" / "00";
  fs::create_directories(seq);
  fs::create_directories(dir / "data" / "poses");
  const fs::path run = dir / "run";
  fs::create_directories(run / "samples");
  std::ofstream times(seq / "times.txt"), poses(dir / "data" / "poses" / "00.txt"), est(run / "trajectory.tum"),
      kf(run / "keyframes.tum");
  for (int i = 0; i < 50; ++i) {
    times << 0.1 * i << "\n";
    poses << "1 0 0 0 0 1 0 0 0 0 1 " << i << "\n";
    const double e = i >= 25 ? 0.3 : 0.0;
    est << 0.1 * i << " " << (2 + e) / 2 << " 0 " << i / 2.0 << " 0 0 0 1\n";
    if (i % 10 == 0) kf << 0.1 * i << " " << (2 + e) / 2 << " 0 " << i / 2.0 << " 0 0 0 1\n";
  }
  json s = {{"frames", 50},
            {"tracked", 50},
            {"dataset", "test"},
            {"dataset_path", seq.string()},
            {"ape", {{"sim3_rmse", 0.2}, {"se3_rmse", 5.0}, {"sim3_scale", 2.0}}},
            {"detections", {{"static", 1}, {"dynamic", 1}, {"unknown", 0}}},
            {"world", {{"metric", true}, {"metric_from_frame", 3}}},
            {"map_points", {{"total", 3}, {"on_static_objects", 1}}},
            {"evaluation",
             {{"alignment",
               {{"type", "sim3"},
                {"scale", 2.0},
                {"rotation", {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}},
                {"translation", {-2, 0, 0}}}}}}};
  std::ofstream(run / "summary.json") << s.dump(1);
  std::ofstream(run / "timing.csv")
      << "frame,load_ms,detector_ms,backend_ms,total_ms,rss_mb\n0,1.0,,10.0,11.0,80.5\n1,3.0,2.0,20.0,25.0,81.0\n"
         "2,2.0,4.0,30.0,36.0,81.5\n";
  std::ofstream(run / "objects.txt") << "10 7 Car 0 0 0 1 2 3 4 1.5 1.8 4.0 0 1.5 10 0 0.9 static\n"
                                        "12 8 Car 0 0 0 1 2 3 4 1.5 1.8 4.0 3 1.5 20 0 0.9 dynamic\n";
  std::ofstream(run / "map_points.ply")
      << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
         "property int observations\nend_header\n1 0 5 10 20 30 2\n2 -1 6 40 50 60 3\n"
         "0 0 7 70 80 90 2\n";
  cv::imwrite((run / "samples" / "000010.png").string(), cv::Mat(20, 40, CV_8UC3, cv::Scalar(0, 0, 255)));
  cv::imwrite((run / "samples" / "000020.jpg").string(), cv::Mat(20, 40, CV_8UC3, cv::Scalar(0, 255, 0)));
  std::ofstream(run / "samples" / "notes.txt") << "not a frame\n";
  return run;
}

json runData(const fs::path& report, int k) {
  std::string s = readText(report / "data" / ("run_" + std::to_string(k) + ".js"));
  const std::string head = "BESLAM_REPORT.addRun(" + std::to_string(k) + ", ";
  EXPECT_EQ(s.rfind(head, 0), 0u);
  EXPECT_EQ(s.substr(s.size() - 3), ");\n");
  return json::parse(s.substr(head.size(), s.size() - head.size() - 3));
}

}  // namespace

TEST(Report, HandMadeRunFigures) {
  const fs::path dir = tempDir("handmade");
  const fs::path run = makeRun(dir);
  beslam::report::writeRunReport(run.string(), "");
  const fs::path rep = run / "report";
  for (const char* f :
       {"index.html", "lib/three.min.js", "lib/OrbitControls.js", "lib/chart.min.js", "samples/0/000010.png"})
    EXPECT_TRUE(fs::exists(rep / f)) << f;
  const std::string page = readText(rep / "index.html");
  EXPECT_EQ(page.find("/*BESLAM_INDEX*/null"), std::string::npos);
  EXPECT_EQ(page.find("http://"), std::string::npos);  // nothing loads from a network
  EXPECT_EQ(page.find("https://"), std::string::npos);

  const json d = runData(rep, 0);
  const json& s = d["series"];
  ASSERT_EQ(s["ape"].size(), 50u);
  for (int i = 0; i < 50; ++i) EXPECT_NEAR(s["ape"][i].get<double>(), i >= 25 ? 0.3 : 0.0, 1e-9) << i;
  ASSERT_EQ(s["gt"].size(), 50u);
  EXPECT_NEAR(s["est"][30][0].get<double>(), 0.3, 1e-9);
  EXPECT_NEAR(s["est"][30][1].get<double>(), 30.0, 1e-9);
  // Windows of 20 steps: the estimate travels half the truth's distance as run, the same after alignment,
  // except the windows holding the 0.3 m sideways step at frame 25.
  ASSERT_EQ(s["scale_frame"].size(), 30u);
  for (size_t k = 0; k < 30; ++k) {
    const int f = s["scale_frame"][k];
    const bool step = f >= 25 && f - 20 < 25;
    const double aligned = step ? (19 + std::sqrt(1.09)) / 20 : 1.0;
    EXPECT_NEAR(s["scale_aligned"][k].get<double>(), aligned, 1e-3) << f;
    EXPECT_NEAR(s["scale_raw"][k].get<double>(), aligned / 2, 1e-3) << f;
  }
  // Timing: medians per stage over the frames that ran it.
  std::map<std::string, double> med;
  for (const auto& st : d["timing"]["stages"]) med[st["name"]] = st["median"];
  EXPECT_EQ(med["load"], 2.0);
  EXPECT_EQ(med["detector"], 3.0);
  EXPECT_EQ(med["backend"], 20.0);
  EXPECT_EQ(med.count("total"), 0u);
  EXPECT_EQ(med.size(), 3u) << "rss_mb is memory, not a stage";
  EXPECT_EQ(d["counts"]["static"], json({1, 0}));
  EXPECT_EQ(d["counts"]["dynamic"], json({0, 1}));
  // The static box of track 7 (frame 10, estimate at (1, 0, 5)): 4 m long along x, 1.8 m wide, 1.5 m tall.
  ASSERT_EQ(d["boxes"].size(), 2u);
  const json& b = d["boxes"][0];
  EXPECT_EQ(b["state"], "static");
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9, z0 = 1e9, z1 = -1e9;
  for (int k = 0; k < 8; ++k) {
    const double x = b["corners"][3 * k], y = b["corners"][3 * k + 1], z = b["corners"][3 * k + 2];
    x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y), z0 = std::min(z0, z),
    z1 = std::max(z1, z);
  }
  EXPECT_NEAR(x0, -1.0, 1e-9);
  EXPECT_NEAR(x1, 3.0, 1e-9);
  EXPECT_NEAR(y0, 0.0, 1e-9);
  EXPECT_NEAR(y1, 1.5, 1e-9);
  EXPECT_NEAR(z0, 14.1, 1e-9);
  EXPECT_NEAR(z1, 15.9, 1e-9);
  EXPECT_EQ(d["view"]["map"]["positions"], json({1, 0, 5, 2, -1, 6, 0, 0, 7}));
  EXPECT_EQ(d["view"]["map"]["colors"], json({10, 20, 30, 40, 50, 60, 70, 80, 90}));
  EXPECT_EQ(d["view"]["keyframes"].size(), 5u);
  // Ground truth in the map's frame: the inverse alignment ((x + 2) / 2, y / 2, z / 2).
  EXPECT_NEAR(d["view"]["ground_truth"][3 * 10 + 2].get<double>(), 5.0, 1e-9);
  EXPECT_NEAR(d["view"]["ground_truth"][3 * 10].get<double>(), 1.0, 1e-9);
  EXPECT_EQ(d["samples"], json({"samples/0/000010.png", "samples/0/000020.jpg"}));
}

TEST(Report, ErrorsNameTheFile) {
  const fs::path dir = tempDir("errors");
  fs::create_directories(dir / "empty");
  try {
    beslam::report::writeRunReport((dir / "empty").string(), "");
    FAIL();
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "empty" / "summary.json").string()), std::string::npos) << e.what();
  }
  const fs::path run = makeRun(dir);
  {
    std::ofstream ply(run / "map_points.ply");
    ply << "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nend_header\n";
  }
  try {
    beslam::report::writeRunReport(run.string(), (dir / "rep").string());
    FAIL();
  } catch (const beslam::Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind((run / "map_points.ply").string() + ": only ASCII", 0), 0u) << e.what();
  }
  fs::remove(run / "map_points.ply");
  setenv("BESLAM_JS_DIR", (dir / "nojs").string().c_str(), 1);
  try {
    beslam::report::writeRunReport(run.string(), (dir / "rep").string());
    FAIL();
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("libjs-three"), std::string::npos) << e.what();
  }
  unsetenv("BESLAM_JS_DIR");
  EXPECT_FALSE(fs::exists(dir / "rep" / "index.html"));
}

// Probes: a run without a trajectory, or one that failed, drew empty plots without a word; a garbled
// timing.csv too. The first are warnings naming the file, the last an error naming file and line.
TEST(Report, WhatTheReportCannotShowIsSaid) {
  const fs::path dir = tempDir("cannot_show");
  const fs::path run = makeRun(dir);
  fs::remove(run / "trajectory.tum");
  {
    json s = json::parse(readText(run / "summary.json"));
    s["status"] = "failed: frame 3: cannot read image";
    std::ofstream(run / "summary.json") << s.dump(1);
  }
  const std::vector<std::string> warnings = beslam::report::writeRunReport(run.string(), (dir / "rep1").string());
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0],
            (run / "summary.json").string() +
                ": the run did not complete (failed: frame 3: cannot read image); the report shows what it "
                "left");
  EXPECT_EQ(warnings[1],
            (run / "trajectory.tum").string() + ": missing; the trajectory, APE and scale plots are empty");
  std::ostringstream out, err;
  EXPECT_EQ(beslam::report::runReportCommand({run.string(), "--out", (dir / "rep2").string()}, out, err), 0);
  EXPECT_NE(err.str().find("beslam report: warning: " + (run / "trajectory.tum").string() + ": missing"),
            std::string::npos)
      << err.str();
  EXPECT_TRUE(fs::exists(dir / "rep2" / "index.html"));

  std::ofstream(run / "timing.csv") << "frame,load_ms,total_ms\n0,1.0,2.0\n1,3.0\n";
  std::ostringstream out2, err2;
  EXPECT_EQ(beslam::report::runReportCommand({run.string(), "--out", (dir / "rep3").string()}, out2, err2), 1);
  EXPECT_EQ(err2.str(),
            "beslam: error: " + (run / "timing.csv").string() + ":3: a row of 2 fields under a header of 3\n");
  std::ofstream(run / "timing.csv") << "<html>not a table</html>\n";
  std::ostringstream out3, err3;
  EXPECT_EQ(beslam::report::runReportCommand({run.string(), "--out", (dir / "rep4").string()}, out3, err3), 1);
  EXPECT_NE(err3.str().find((run / "timing.csv").string() + ":1: not a timing.csv"), std::string::npos) << err3.str();
}

// Headless Chromium, as a person would open the report: a real (short) BE-SLAM run on synthetic data.
// BESLAM_REPORT_RUN=DIR uses an existing run folder instead (how docs/images/report.png was made).
TEST(ReportBrowser, ChromiumDrawsPlotsAndThe3DView) {
  if (shell("command -v chromium > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "chromium is not installed (scripts/install-deps.sh installs it): browser test skipped";
  const fs::path dir = tempDir("browser");
  fs::path run;
  if (const char* given = std::getenv("BESLAM_REPORT_RUN"); given && *given) {
    run = given;
  } else {
    run = dir / "run";
    const fs::path cache = fs::path(BESLAM_BINARY_DIR) / "test-bench-synth-cache";
    const std::string cmd = std::string(BESLAM_BINARY_DIR) + "/bin/beslam run " + BESLAM_SOURCE_DIR +
                            "/configs/ablation/synth_beslam.yaml --quiet --out " + run.string() +
                            " --set dataset.root=" + cache.string() +
                            " --set dataset.sequence=dynamic_street"
                            " --set dataset.synth_set=lidar.enabled=false,camera.colour=false,frames=60 > " +
                            (dir / "run.log").string() + " 2>&1";
    ASSERT_EQ(shell(cmd), 0) << readText(dir / "run.log");
  }
  const fs::path rep = dir / "report";
  ASSERT_EQ(shell(std::string(BESLAM_BINARY_DIR) + "/bin/beslam report " + run.string() + " --out " + rep.string() +
                  " > " + (dir / "report.log").string() + " 2>&1"),
            0)
      << readText(dir / "report.log");
  const std::string chromium =
      "chromium --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader --disable-quic --no-first-run "
      "--disable-background-networking --disable-component-update --disable-sync --hide-scrollbars "
      "--window-size=1280,1990 --virtual-time-budget=15000 --user-data-dir=" +
      (dir / "profile").string() + " ";
  const std::string url = "file://" + fs::absolute(rep / "index.html").string();
  ASSERT_EQ(shell(chromium + "--dump-dom " + url + " > " + (dir / "dom.html").string() + " 2> " +
                  (dir / "chromium1.log").string()),
            0)
      << readText(dir / "chromium1.log");
  const std::string dom = readText(dir / "dom.html");
  EXPECT_NE(dom.find("data-status=\"ready\""), std::string::npos) << "the page did not finish drawing";
  std::smatch m;
  ASSERT_TRUE(std::regex_search(dom, m, std::regex("<pre id=\"errors\"[^>]*>([^<]*)</pre>")));
  EXPECT_EQ(m[1].str(), "") << "JavaScript errors: " << m[1].str();
  ASSERT_TRUE(std::regex_search(dom, m, std::regex("<pre id=\"layout\"[^>]*>([^<]*)</pre>")));
  const json layout = json::parse(m[1].str());

  ASSERT_EQ(shell(chromium + "--screenshot=" + (dir / "screenshot.png").string() + " " + url + " > " +
                  (dir / "chromium2.log").string() + " 2>&1"),
            0)
      << readText(dir / "chromium2.log");
  const cv::Mat shot = cv::imread((dir / "screenshot.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(shot.empty());
  auto region = [&](const char* id) {
    const json& r = layout[id];
    const cv::Rect rect(r[0], r[1], r[2], r[3]);
    EXPECT_TRUE((rect & cv::Rect(0, 0, shot.cols, shot.rows)) == rect) << id << " is outside the screenshot";
    return shot(rect & cv::Rect(0, 0, shot.cols, shot.rows));
  };
  // Pixels near an RGB colour (the series' colours in the page).
  auto near = [](const cv::Mat& img, int r, int g, int b) {
    int n = 0;
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x) {
        const cv::Vec3b p = img.at<cv::Vec3b>(y, x);
        n += std::abs(p[2] - r) < 40 && std::abs(p[1] - g) < 40 && std::abs(p[0] - b) < 40;
      }
    return n;
  };
  EXPECT_GT(near(region("c_top"), 255, 159, 28), 50) << "no estimate line in the top view";
  EXPECT_GT(near(region("c_top"), 46, 196, 182), 50) << "no ground truth line in the top view";
  EXPECT_GT(near(region("c_ape"), 230, 57, 70), 50) << "no APE line";
  EXPECT_GT(near(region("c_scale"), 77, 124, 255), 50) << "no scale line";
  EXPECT_GT(near(region("c_timing"), 77, 124, 255), 200) << "no timing bars";
  EXPECT_GT(near(region("c_counts"), 59, 178, 115) + near(region("c_counts"), 230, 57, 70) +
                near(region("c_counts"), 141, 153, 174),
            50)
      << "no detection bars";
  // The 3D view: mostly the dark background, with map points and the orange trajectory drawn on it.
  const cv::Mat view = region("c_3d");
  const int background = near(view, 20, 22, 27);
  const int drawn = view.rows * view.cols - background;
  EXPECT_GT(background, view.rows * view.cols / 2) << "the 3D canvas is not the viewer's background";
  EXPECT_GT(drawn, 500) << "the 3D canvas is empty";
  EXPECT_GT(near(view, 255, 159, 28), 30) << "no trajectory in the 3D view";
}
