// Writing a sequence (KITTI layouts), previews, the cached default sequence, and `beslam synth`.
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <thread>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"
#include "beslam/common/yaml_set.hpp"
#include "beslam/sdk/cli_args.hpp"
#include "beslam/sim/synth.hpp"
#include "presets.hpp"
#include "world.hpp"

namespace beslam::sim {
namespace {

std::string frameName(int i, const char* ext) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06d%s", i, ext);
  return buf;
}

std::string fmt(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.12e", v);
  return buf;
}

std::string row34(const Eigen::Matrix<double, 3, 4>& M) {
  std::string s;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) s += (s.empty() ? "" : " ") + fmt(M(r, c));
  return s;
}

void writePng(const std::string& path, const cv::Mat& img) {
  std::vector<uchar> buf;
  // OpenCV's speed settings, which it takes when no PNG parameter is given: the Sub filter on every row,
  // zlib level 1, run-length matching. Against level 1 with libpng's adaptive filters (what these files
  // were before): urban_loop's grey frames encode in 7.6 instead of 11.9 ms and decode in 3.8 instead of
  // 4.6 ms (a run reads every frame), for 8 % more bytes; the pixels are the same.
  if (!cv::imencode(".png", img, buf)) throwAt(path, "PNG encoding failed");
  writeFileAtomic(path, std::string(buf.begin(), buf.end()));
}

std::string labelRow(int frame, const ObjectLabel& L) {
  char buf[512];
  std::snprintf(buf, sizeof buf, "%d %d %s %.6f %d %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f\n",
                frame, L.track_id, L.type.c_str(), L.truncated, L.occluded, L.alpha, L.x1, L.y1, L.x2, L.y2, L.h, L.w,
                L.l, L.location.x(), L.location.y(), L.location.z(), L.ry);
  return buf;
}

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ULL;
  return h;
}

// The sequence's folders.
void makeSequenceDirectories(const SynthConfig& config, const std::string& out_dir, const std::string& seqDir) {
  makeDirectories(out_dir + "/poses");
  makeDirectories(seqDir);
  if (config.camera.grey) makeDirectories(seqDir + "/image_0");
  if (config.camera.colour) makeDirectories(seqDir + "/image_2");
  if (config.lidar.enabled) makeDirectories(seqDir + "/velodyne");
  if (config.output.depth) makeDirectories(seqDir + "/depth");
  makeDirectories(seqDir + "/instance");
  makeDirectories(seqDir + "/label_02");
  makeDirectories(seqDir + "/objects");
}

// Renders frame i into fr and writes its images, depth and scan; returns its label rows.
std::string writeFrame(const Synthesizer& synth, const SynthConfig& config, const std::string& seqDir, int i,
                       FrameRender& fr) {
  synth.render(i, fr);
  if (config.camera.grey) writePng(seqDir + "/image_0/" + frameName(i, ".png"), fr.grey);
  if (config.camera.colour) writePng(seqDir + "/image_2/" + frameName(i, ".png"), fr.colour);
  writePng(seqDir + "/instance/" + frameName(i, ".png"), fr.instance);
  if (config.output.depth) {
    cv::Mat d16(fr.depth.size(), CV_16UC1);
    for (int y = 0; y < d16.rows; ++y)
      for (int x = 0; x < d16.cols; ++x)
        d16.at<std::uint16_t>(y, x) =
            static_cast<std::uint16_t>(std::min(65535.0, std::round(fr.depth.at<float>(y, x) * 256.0)));
    writePng(seqDir + "/depth/" + frameName(i, ".png"), d16);
  }
  if (config.lidar.enabled)
    writeFileAtomic(seqDir + "/velodyne/" + frameName(i, ".bin"),
                    std::string(reinterpret_cast<const char*>(fr.lidar.data()), fr.lidar.size() * sizeof(float)));
  std::string rows;
  for (const auto& L : fr.labels) rows += labelRow(i, L);
  return rows;
}

// Frames in parallel; each frame is a pure function of (config, index), so the bytes do not depend on
// which worker renders it. Labels are collected per frame (returned in frame order).
std::vector<std::string> writeFrames(const Synthesizer& synth, const SynthConfig& config, const std::string& seqDir,
                                     std::ostream* progress) {
  const int n = config.frames;
  std::vector<std::string> labelText(static_cast<std::size_t>(n));
  std::atomic<int> next{0}, done{0};
  std::mutex errorMutex;
  std::string firstError;
  auto worker = [&] {
    FrameRender fr;  // buffers reused from frame to frame
    while (true) {
      const int i = next.fetch_add(1);
      if (i >= n) return;
      {
        std::lock_guard<std::mutex> lock(errorMutex);
        if (!firstError.empty()) return;
      }
      try {
        labelText[static_cast<std::size_t>(i)] = writeFrame(synth, config, seqDir, i, fr);
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(errorMutex);
        if (firstError.empty()) firstError = e.what();
        return;
      }
      const int d = ++done;
      if (progress) {
        std::lock_guard<std::mutex> lock(errorMutex);
        *progress << "\rbeslam synth: frame " << d << "/" << n << std::flush;
      }
    }
  };
  std::vector<std::thread> threads;
  const int nt = std::max(1, std::min(config.output.threads, n));
  for (int k = 1; k < nt; ++k) threads.emplace_back(worker);
  worker();
  for (auto& th : threads) th.join();
  if (progress) *progress << "\n";
  if (!firstError.empty()) throw Error(firstError);
  return labelText;
}

// Sequence-level files: labels, times, ego poses, calibration.
void writeSequenceFiles(const Synthesizer& synth, const SynthConfig& config, const std::string& out_dir,
                        const std::string& seqDir, const std::vector<std::string>& labelText) {
  const int n = config.frames;
  std::string labels;
  for (const auto& s : labelText) labels += s;
  writeFileAtomic(seqDir + "/label_02/" + config.sequence + ".txt", labels);
  std::ostringstream times, poses;
  for (int i = 0; i < n; ++i) {
    times << fmt(i / config.rate_hz) << "\n";
    poses << row34(synth.T_world_cam(i).matrix().topRows<3>()) << "\n";
  }
  writeFileAtomic(seqDir + "/times.txt", times.str());
  writeFileAtomic(out_dir + "/poses/" + config.sequence + ".txt", poses.str());
  {
    const Eigen::Matrix<double, 3, 4> P = synth.projection();
    Eigen::Matrix<double, 3, 4> Tr = synth.T_cam_velo().matrix().topRows<3>();
    std::ostringstream c;
    for (const char* name : {"P0", "P1", "P2", "P3"}) c << name << ": " << row34(P) << "\n";
    c << "R0_rect:";
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) c << " " << fmt(r == k ? 1.0 : 0.0);
    c << "\nTr_velo_to_cam: " << row34(Tr) << "\nTr: " << row34(Tr) << "\n";
    writeFileAtomic(seqDir + "/calib.txt", c.str());
  }
}

// Objects: motion flags, poses, meshes.
void writeObjectFiles(const Synthesizer& synth, const SynthConfig& config, const std::string& seqDir) {
  const int n = config.frames;
  std::ostringstream motion, opose, oinfo;
  motion << "# frame track_id moving speed_m_s\n";
  opose << "# frame track_id T_world_obj (3x4 row-major; KITTI world = cam0 at frame 0; object frame x fwd, y down, z "
           "left)\n";
  oinfo << "# track_id type shape behaviour length width height\n";
  for (const auto& o : synth.objects())
    oinfo << o.track_id << " " << o.type << " " << o.shape << " " << behaviourName(o.behaviour) << " " << o.length
          << " " << o.width << " " << o.height << "\n";
  for (int i = 0; i < n; ++i)
    for (const auto& o : synth.objects()) {
      const ObjectState st = synth.objectState(o.track_id, i);
      char buf[96];
      std::snprintf(buf, sizeof buf, "%d %d %d %.6f\n", i, o.track_id, st.moving ? 1 : 0, st.speed);
      motion << buf;
      opose << i << " " << o.track_id << " " << row34(st.T_world_obj.matrix().topRows<3>()) << "\n";
    }
  writeFileAtomic(seqDir + "/objects_motion.txt", motion.str());
  writeFileAtomic(seqDir + "/objects/poses.txt", opose.str());
  writeFileAtomic(seqDir + "/objects/objects.txt", oinfo.str());
  for (const auto& o : synth.objects()) {
    if (o.behaviour == Behaviour::Pedestrian) continue;
    std::vector<Eigen::Vector3f> v;
    std::vector<std::array<int, 3>> f;
    synth.objectMesh(o.track_id, v, f);
    std::ostringstream ply;
    ply << "ply\nformat ascii 1.0\ncomment beslam synth car " << o.track_id << " (" << o.shape
        << "), KITTI object frame: x forward, y down, z left, origin at the bottom centre\nelement vertex " << v.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << f.size()
        << "\nproperty list uchar int vertex_indices\nend_header\n";
    ply << std::setprecision(7);
    for (const auto& p : v) ply << p.x() << " " << p.y() << " " << p.z() << "\n";
    for (const auto& t : f) ply << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
    char name[32];
    std::snprintf(name, sizeof name, "car_%04d.ply", o.track_id);
    writeFileAtomic(seqDir + "/objects/" + name, ply.str());
  }
}

// Manifest: what was placed against what was asked for, the ego's loop, and the config.
void writeManifest(const SynthConfig& config, const SequenceSummary& sum, const std::string& seqDir) {
  const int n = config.frames;
  YAML::Emitter m;
  m << YAML::BeginMap;
  m << YAML::Key << "generator" << YAML::Value << "beslam synth";
  m << YAML::Key << "seed" << YAML::Value << config.seed;
  m << YAML::Key << "frames" << YAML::Value << n;
  m << YAML::Key << "counts" << YAML::Value << YAML::BeginMap;
  m << YAML::Key << "parked" << YAML::Value << sum.parked;
  m << YAML::Key << "driving" << YAML::Value << sum.driving;
  m << YAML::Key << "stop_and_go" << YAML::Value << sum.stop_and_go;
  m << YAML::Key << "pedestrians" << YAML::Value << sum.pedestrians;
  m << YAML::EndMap;
  m << YAML::Key << "requested" << YAML::Value << YAML::BeginMap;
  m << YAML::Key << "parked" << YAML::Value << config.objects.parked;
  m << YAML::Key << "driving" << YAML::Value << config.objects.driving;
  m << YAML::Key << "stop_and_go" << YAML::Value << config.objects.stop_and_go;
  m << YAML::Key << "pedestrians" << YAML::Value << config.objects.pedestrians;
  m << YAML::EndMap;
  m << YAML::Key << "ego" << YAML::Value << YAML::BeginMap;
  m << YAML::Key << "loop_length_m" << YAML::Value << sum.loop_length_m;
  m << YAML::Key << "distance_m" << YAML::Value << sum.distance_m;
  m << YAML::Key << "laps" << YAML::Value << sum.laps;
  m << YAML::EndMap;
  m << YAML::EndMap;
  // Every parameter that shapes the data, verbatim (the worker count does not, so it is left out).
  std::string text = std::string(m.c_str()) + "\nconfig:\n";
  std::istringstream cfgText(synthConfigToYaml(config));
  std::string line;
  while (std::getline(cfgText, line))
    if (line.rfind("  threads:", 0) != 0 && !line.empty()) text += "  " + line + "\n";
  writeFileAtomic(seqDir + "/manifest.yaml", text);
}

}  // namespace

SequenceSummary generateSequence(const SynthConfig& config, const std::string& out_dir, std::ostream* progress) {
  const Synthesizer synth(config);
  const std::string seqDir = out_dir + "/sequences/" + config.sequence;
  makeSequenceDirectories(config, out_dir, seqDir);
  const std::vector<std::string> labelText = writeFrames(synth, config, seqDir, progress);
  writeSequenceFiles(synth, config, out_dir, seqDir, labelText);
  writeObjectFiles(synth, config, seqDir);
  const SequenceSummary sum = synth.summary();
  writeManifest(config, sum, seqDir);
  return sum;
}

void writePreview(const SynthConfig& config, int frame, const std::string& dir) {
  SynthConfig c = config;
  c.lidar.enabled = true;
  c.camera.colour = c.camera.grey = true;
  const Synthesizer synth(c);
  if (frame < 0 || frame >= synth.frameCount())
    throw Error("--frame " + std::to_string(frame) + ": outside the sequence");
  const FrameRender fr = synth.render(frame);
  makeDirectories(dir);
  std::vector<uchar> buf;
  cv::imencode(".jpg", fr.colour, buf, {cv::IMWRITE_JPEG_QUALITY, 88});
  writeFileAtomic(dir + "/synth_frame.jpg", std::string(buf.begin(), buf.end()));
  // Instance ids in false colour, 2D boxes (green: unoccluded, orange: occluded), the scene's depth
  // edges faintly in the background (kept plain so the PNG stays small).
  cv::Mat mask(fr.grey.size(), CV_8UC3, cv::Scalar(40, 40, 40));
  for (int y = 1; y < mask.rows; ++y)
    for (int x = 1; x < mask.cols; ++x) {
      const float d = fr.depth.at<float>(y, x), dl = fr.depth.at<float>(y, x - 1), du = fr.depth.at<float>(y - 1, x);
      if (std::abs(d - dl) > 0.05f * std::max(d, dl) || std::abs(d - du) > 0.05f * std::max(d, du))
        mask.at<cv::Vec3b>(y, x) = cv::Vec3b(110, 110, 110);
    }
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x) {
      const int id = fr.instance.at<std::uint16_t>(y, x);
      if (!id) continue;
      const std::uint32_t h = detail::hash32(static_cast<std::uint32_t>(id) * 2654435761U);
      mask.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uchar>(80 + (h & 127)), static_cast<uchar>(80 + ((h >> 8) & 175)),
                    static_cast<uchar>(80 + ((h >> 16) & 175)));
    }
  for (const auto& L : fr.labels)
    cv::rectangle(mask, cv::Point(static_cast<int>(L.x1), static_cast<int>(L.y1)),
                  cv::Point(static_cast<int>(L.x2), static_cast<int>(L.y2)),
                  L.occluded == 0 ? cv::Scalar(0, 255, 0) : cv::Scalar(0, 200, 255), 1);
  buf.clear();
  cv::imencode(".png", mask, buf, {cv::IMWRITE_PNG_COMPRESSION, 9});
  writeFileAtomic(dir + "/synth_mask.png", std::string(buf.begin(), buf.end()));
  // Bird's-eye view of the scan: 80 m x 80 m round the sensor, 0.16 m per pixel, coloured by height.
  const int S = 500;
  const double res = 0.16;
  cv::Mat bev(S, S, CV_8UC3, cv::Scalar(20, 20, 20));
  for (std::size_t i = 0; i + 3 < fr.lidar.size(); i += 4) {
    const float x = fr.lidar[i], y = fr.lidar[i + 1], z = fr.lidar[i + 2];
    const int px = static_cast<int>(S / 2 - y / res), py = static_cast<int>(S / 2 - x / res);
    if (px < 0 || py < 0 || px >= S || py >= S) continue;
    const double hgt = std::clamp((z + 1.73) / 4.0, 0.0, 1.0);
    bev.at<cv::Vec3b>(py, px) = cv::Vec3b(static_cast<uchar>(255 * (1 - hgt)), static_cast<uchar>(120 + 135 * hgt),
                                          static_cast<uchar>(255 * hgt));
  }
  cv::circle(bev, cv::Point(S / 2, S / 2), 3, cv::Scalar(255, 255, 255), -1);
  // Ground-truth boxes of labelled objects, projected into the LiDAR frame.
  const Eigen::Isometry3d T_velo_cam = synth.T_cam_velo().inverse();
  for (const auto& L : fr.labels) {
    std::vector<cv::Point> poly;
    for (int k = 0; k < 4; ++k) {
      const double lx = (k == 0 || k == 3 ? 0.5 : -0.5) * L.l, lz = (k < 2 ? 0.5 : -0.5) * L.w;
      const Eigen::Vector3d pc(L.location.x() + std::cos(L.ry) * lx + std::sin(L.ry) * lz, L.location.y(),
                               L.location.z() - std::sin(L.ry) * lx + std::cos(L.ry) * lz);
      const Eigen::Vector3d pv = T_velo_cam * pc;
      poly.emplace_back(static_cast<int>(S / 2 - pv.y() / res), static_cast<int>(S / 2 - pv.x() / res));
    }
    cv::polylines(bev, poly, true, cv::Scalar(0, 255, 0), 1);
  }
  buf.clear();
  cv::imencode(".png", bev, buf, {cv::IMWRITE_PNG_COMPRESSION, 9});
  writeFileAtomic(dir + "/synth_lidar_bev.png", std::string(buf.begin(), buf.end()));
}

std::string ensureDefaultSequence(const std::string& cache_dir, const std::string& name, std::ostream* progress) {
  return ensureSequence(cache_dir, presetConfig(name), name, progress);
}

std::string ensureSequence(const std::string& cache_dir, const SynthConfig& config, const std::string& name,
                           std::ostream* progress) {
  const std::string text = synthConfigToYaml(config);
  char hash[20];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(fnv1a(text + "beslam-synth-v1")));
  const std::string dir = cache_dir + "/" + name + "-" + std::string(hash).substr(0, 12);
  const std::string marker = dir + "/COMPLETE";
  if (std::filesystem::exists(marker)) return dir;
  const std::string tmp = dir + ".partial." + std::to_string(::getpid());
  std::error_code ec;
  std::filesystem::remove_all(tmp, ec);
  generateSequence(config, tmp, progress);
  writeFileAtomic(tmp + "/COMPLETE", text);
  // Several runs may render the same sequence at once (parallel ablations): the first to finish keeps its
  // folder, which others may already be reading; a later one discards its own. Only a folder without the
  // marker (an interrupted render) is replaced.
  if (std::filesystem::exists(marker)) {
    std::filesystem::remove_all(tmp, ec);
    return dir;
  }
  std::filesystem::remove_all(dir, ec);
  std::filesystem::rename(tmp, dir, ec);
  if (ec) {
    std::filesystem::remove_all(tmp, ec);
    if (std::filesystem::exists(marker)) return dir;  // another process won the race
    throwAt(dir, "cannot move the generated sequence into place");
  }
  return dir;
}

int runSynthCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  const char* usage =
      "usage: beslam synth --config FILE|PRESET --out DIR [--set key=value]... [--preview DIR [--frame N]]\n"
      "Renders a deterministic synthetic driving sequence with ground truth in KITTI layouts.\n"
      "  --config FILE   a YAML config (see configs/synth/), or a preset name: ";
  auto printUsage = [&](std::ostream& o) {
    o << usage;
    std::string list;
    for (const auto& n : presetNames()) list += (list.empty() ? "" : ", ") + n;
    o << list << "\n"
      << "  --out DIR       output root (DIR/sequences/NN, DIR/poses/NN.txt)\n"
      << "  --set k=v       override a config key, e.g. --set frames=50 --set lidar.enabled=false\n"
      << "  --preview DIR   write synth_frame.jpg, synth_mask.png and synth_lidar_bev.png of one frame\n"
      << "  --frame N       the frame to preview (default 0)\n";
  };
  std::string configPath, outDir, previewDir;
  int previewFrame = 0;
  std::vector<std::string> sets;
  try {
    const bool help = cli::forEachFlag(
        args, [&] { printUsage(out); },
        [&](const std::string& a, std::size_t& i) {
          if (a == "--config")
            configPath = cli::nextValue(args, i);
          else if (a == "--out")
            outDir = cli::nextValue(args, i);
          else if (a == "--set")
            sets.push_back(cli::nextValue(args, i));
          else if (a == "--preview")
            previewDir = cli::nextValue(args, i);
          else if (a == "--frame") {
            const std::string v = cli::nextValue(args, i);
            try {
              std::size_t pos = 0;
              previewFrame = std::stoi(v, &pos);
              if (pos != v.size()) throw std::invalid_argument("");
            } catch (...) {
              throw std::invalid_argument("--frame expects an integer, got '" + v + "'");
            }
          } else
            throw std::invalid_argument("unknown argument '" + a + "' (see --help)");
        });
    if (help) return 0;
  } catch (const std::invalid_argument& e) {
    err << "beslam synth: " << e.what() << "\n";
    return 2;
  }
  if (configPath.empty() || (outDir.empty() && previewDir.empty())) {
    err << "beslam synth: --config and --out (or --preview) are required\n";
    printUsage(err);
    return 2;
  }
  try {
    SynthConfig config;
    const auto names = presetNames();
    if (!std::filesystem::exists(configPath) && std::find(names.begin(), names.end(), configPath) != names.end()) {
      // A preset by name: apply --set on its YAML text.
      YAML::Node root;
      for (const auto& p : detail::presetTexts())
        if (p.first == configPath) root = YAML::Load(p.second);
      for (const auto& s : sets) applySetOverride(root, s);
      config = synthConfigFromYaml(root, "preset " + configPath);
    } else {
      config = loadSynthConfig(configPath, sets);
    }
    if (!previewDir.empty()) {
      writePreview(config, previewFrame, previewDir);
      out << "beslam synth: preview of frame " << previewFrame << " written to " << previewDir << "\n";
    }
    if (!outDir.empty()) {
      const bool tty = &err == &std::cerr && ::isatty(STDERR_FILENO);
      const SequenceSummary s = generateSequence(config, outDir, tty ? &err : nullptr);
      out << "beslam synth: " << s.frames << " frames in " << outDir << "/sequences/" << config.sequence << " (parked "
          << s.parked << ", driving " << s.driving << ", stop-and-go " << s.stop_and_go << ", pedestrians "
          << s.pedestrians << "; " << std::fixed << std::setprecision(1) << s.distance_m << " m driven, "
          << std::setprecision(2) << s.laps << " laps)\n";
    }
  } catch (const std::exception& e) {
    err << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace beslam::sim
