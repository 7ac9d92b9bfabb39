// orb_run_kitti <sequence_dir> <poses.txt|-> <out.txt> [--threaded] [--frames N] [--seed S] [--quiet]
// Runs OrbSlam over image_0, writes the final trajectory (KITTI rows prefixed by the frame index), and
// with ground truth prints APE (Sim(3) Umeyama, translation RMSE) and per-stage timing medians.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "beslam/formats/align.hpp"
#include "beslam_orb/orb_slam.hpp"
#include "kitti.hpp"

using namespace beslam::orb;

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// CPU time of the whole process (all threads), ms: a load-independent view of the cost per frame.
double cpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double ape(const std::vector<FramePose>& traj, const std::vector<Eigen::Isometry3d>& gt) {
  std::vector<Eigen::Vector3d> est, ref;
  for (const FramePose& p : traj) {
    if (p.frame_index < 0 || static_cast<size_t>(p.frame_index) >= gt.size()) continue;
    est.push_back(p.T_world_cam.translation());
    ref.push_back(gt[p.frame_index].translation());
  }
  return beslam::formats::positionError(est, ref).rmse;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: orb_run_kitti <sequence_dir> <poses.txt|-> <out.txt> [--threaded] [--concurrent] [--frames N] "
                 "[--seed S]"
                 " [--quiet] [--kf-gap N] [--tri-ratio R] [--ba-max-kfs N] [--features N] [--no-kf-culling]"
                 " [--tri-cos C] [--ba-iters ROBUST REFINE] [--init-parallax DEG] [--init-levels L]"
                 " [--cv-threads N] [--tri-orientation] [--fast INITIAL FALLBACK] [--kf-ratio R] [--ground SIGMA "
                 "MIN_INLIERS]\n";
    return 2;
  }
  const std::string seq = argv[1], gt_path = argv[2], out_path = argv[3];
  Options options;
  size_t max_frames = 0;
  bool quiet = false;
  for (int i = 4; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--threaded"))
      options.threading.threaded_mapping = true;
    else if (!std::strcmp(argv[i], "--concurrent"))
      options.threading.concurrent_mapping = true;
    else if (!std::strcmp(argv[i], "--frames") && i + 1 < argc)
      max_frames = std::stoul(argv[++i]);
    else if (!std::strcmp(argv[i], "--seed") && i + 1 < argc)
      options.seed = std::stoull(argv[++i]);
    else if (!std::strcmp(argv[i], "--quiet"))
      quiet = true;
    else if (!std::strcmp(argv[i], "--cv-threads") && i + 1 < argc)
      cv::setNumThreads(std::stoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--kf-gap") && i + 1 < argc)
      options.tracking.keyframe_min_gap = std::stoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--tri-ratio") && i + 1 < argc)
      options.mapping.triangulation_ratio = std::stod(argv[++i]);
    else if (!std::strcmp(argv[i], "--ba-max-kfs") && i + 1 < argc)
      options.mapping.local_ba_max_keyframes = std::stoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--features") && i + 1 < argc)
      options.extractor.features = std::stoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--no-kf-culling"))
      options.mapping.keyframe_culling = false;
    else if (!std::strcmp(argv[i], "--init-parallax") && i + 1 < argc)
      options.init.min_parallax_deg = std::stod(argv[++i]);
    else if (!std::strcmp(argv[i], "--init-levels") && i + 1 < argc)
      options.init.match_max_level = std::stoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--tri-orientation"))
      options.mapping.triangulation_check_orientation = true;
    else if (!std::strcmp(argv[i], "--tri-cos") && i + 1 < argc)
      options.mapping.triangulation_max_cos_parallax = std::stod(argv[++i]);
    else if (!std::strcmp(argv[i], "--fast") && i + 2 < argc) {
      options.extractor.fast_initial = std::stoi(argv[++i]);
      options.extractor.fast_fallback = std::stoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--kf-ratio") && i + 1 < argc) {
      options.tracking.keyframe_ref_ratio = std::stod(argv[++i]);
    } else if (!std::strcmp(argv[i], "--ground") && i + 2 < argc) {
      options.scale.ground_prior = true;
      options.scale.ground_prior_sigma = std::stod(argv[++i]);
      options.scale.ground_min_inliers = std::stoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--ba-iters") && i + 2 < argc) {
      options.mapping.local_ba_iterations_robust = std::stoi(argv[++i]);
      options.mapping.local_ba_iterations_refine = std::stoi(argv[++i]);
    } else {
      std::cerr << "unknown option " << argv[i] << "\n";
      return 2;
    }
  }
  try {
    const cv::Mat first = cv::imread(kitti::imagePath(seq, 0), cv::IMREAD_GRAYSCALE);
    if (first.empty()) throw std::runtime_error(kitti::imagePath(seq, 0) + ": cannot read");
    const Camera camera = kitti::readCamera(seq + "/calib.txt", first.cols, first.rows);
    const std::vector<double> times = kitti::readTimes(seq + "/times.txt");
    std::vector<Eigen::Isometry3d> gt;
    if (gt_path != "-") gt = kitti::readPoses(gt_path);
    OrbSlam slam(camera, options);
    std::map<std::string, std::vector<double>> stages;
    std::vector<double> track_ms, total_ms, cpu_ms;
    size_t n = 0;
    int lost = 0;
    for (size_t i = 0;; ++i) {
      if (max_frames && i >= max_frames) break;
      const cv::Mat image = cv::imread(kitti::imagePath(seq, i), cv::IMREAD_GRAYSCALE);
      if (image.empty()) break;
      const double ts = i < times.size() ? times[i] : 0.1 * static_cast<double>(i);
      const double cpu0 = cpuMs();
      const TrackResult r = slam.track(image, cv::Mat(), ts, static_cast<int64_t>(i));
      cpu_ms.push_back(cpuMs() - cpu0);
      ++n;
      if (r.state == TrackingState::Lost) ++lost;
      for (auto& [name, ms] : r.stage_ms) {
        stages[name].push_back(ms);
        if (name == "tracking_total") track_ms.push_back(ms);
        if (name == "total") total_ms.push_back(ms);
      }
      if (!quiet) {
        std::cerr << "frame " << i << " state " << static_cast<int>(r.state) << (r.is_keyframe ? " KF" : "   ")
                  << " inliers " << r.tracked_points << " total " << std::fixed << std::setprecision(1)
                  << (total_ms.empty() ? 0.0 : total_ms.back()) << " ms\n";
      }
    }
    slam.finish();
    const auto traj = slam.trajectory();
    std::ofstream out(out_path);
    out << std::setprecision(9);
    for (const FramePose& p : traj) {
      out << p.frame_index << ' ';
      kitti::writePose(out, p.T_world_cam);
    }
    const Statistics st = slam.statistics();
    std::cout << std::fixed << std::setprecision(3);
    std::cout << "frames " << n << " tracked " << traj.size() << " initialised_at " << st.initialised_at_frame
              << " lost_frames " << lost << " resets " << st.resets << " relocalisations " << st.relocalisations
              << " keyframes " << st.keyframes << " culled " << st.keyframes_culled << " points " << st.map_points
              << "\n";
    if (!gt.empty()) {
      std::cout << "ape_rmse_final " << ape(traj, gt) << " m\n";
      std::cout << "ape_rmse_online " << ape(slam.onlineTrajectory(), gt) << " m\n";
      std::cout << "ape_rmse_keyframes " << ape(slam.keyframes(), gt) << " m\n";
      if (!quiet) {  // drift profile: aligned error and relative scale per 20-frame segment
        std::vector<Eigen::Vector3d> est, ref;
        for (const FramePose& p : traj) {
          est.push_back(p.T_world_cam.translation());
          ref.push_back(gt[p.frame_index].translation());
        }
        const auto a = beslam::formats::positionError(est, ref);
        for (size_t i = 0; i + 20 < est.size(); i += (i < 40 ? 5 : 20)) {
          const size_t j = i < 40 ? i + 5 : i + 20;
          const double de = a.alignment.scale * (est[j] - est[i]).norm(), dg = (ref[j] - ref[i]).norm();
          std::cout << "  segment from " << traj[i].frame_index << " error "
                    << (a.alignment.apply(est[i]) - ref[i]).norm() << " scale " << (dg > 0 ? de / dg : 0) << "\n";
        }
      }
    }
    std::cout << "median_ms tracking_total " << median(track_ms) << " total " << median(total_ms) << " mean_total " << (total_ms.empty() ? 0.0 : [&] {
      double s = 0;
      for (double x : total_ms) s += x;
      return s / total_ms.size();
    }()) << "\n";
    {
      double sum = 0;
      for (double x : cpu_ms) sum += x;
      std::cout << "cpu_ms per frame (process, all threads) median " << median(cpu_ms) << " mean "
                << (cpu_ms.empty() ? 0.0 : sum / cpu_ms.size()) << "\n";
    }
    for (auto& [name, v] : stages)
      std::cout << "  stage " << std::setw(20) << name << " median " << median(v) << " max "
                << *std::max_element(v.begin(), v.end()) << " count " << v.size() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "orb_run_kitti: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
