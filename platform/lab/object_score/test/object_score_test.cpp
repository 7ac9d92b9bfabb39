// The object scorer on a hand-made synthetic sequence: three frames, a parked car in view, a parked car
// out of range and a moving car; a run whose world is the truth's turned and shifted (local alignment
// must undo it), with one correct object, one on the moving car and one where there is no car.
#include "beslam/object_score/object_score.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/test/temp_dir.hpp"

using beslam::object_score::Options;
using beslam::object_score::score;

namespace {

std::string row34(const Eigen::Isometry3d& T) {
  std::ostringstream s;
  s.precision(12);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) s << (r || c ? " " : "") << T.matrix()(r, c);
  return s.str();
}

std::string tum(double t, const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.linear());
  std::ostringstream s;
  s.precision(12);
  s << t << ' ' << T.translation().x() << ' ' << T.translation().y() << ' ' << T.translation().z() << ' ' << q.x()
    << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  return s.str();
}

// Box meshes (12 triangles each) of size l, w, h in the KITTI object frame (origin at the bottom centre,
// y down); `buried` adds a second, smaller box inside the first (as a generated car's wheel rims sit in
// its body): the scorer must not count its faces.
std::string boxPly(double l, double w, double h, double y0, bool buried = false) {
  std::ostringstream s;
  const int boxes = buried ? 2 : 1;
  s << "ply\nformat ascii 1.0\nelement vertex " << 8 * boxes
    << "\nproperty float x\nproperty float y\nproperty float z\n"
    << "element face " << 12 * boxes << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (int b = 0; b < boxes; ++b) {
    const double k = b ? 0.5 : 1.0;  // the buried box: half the size, centred in the first
    for (int i = 0; i < 8; ++i)
      s << ((i & 1) ? k * l / 2 : -k * l / 2) << ' ' << ((i & 2) ? y0 - h / 2 - k * h / 2 : y0 - h / 2 + k * h / 2)
        << ' ' << ((i & 4) ? k * w / 2 : -k * w / 2) << '\n';
  }
  const int f[12][3] = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                        {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
  for (int b = 0; b < boxes; ++b)
    for (const auto& t : f) s << "3 " << t[0] + 8 * b << ' ' << t[1] + 8 * b << ' ' << t[2] + 8 * b << '\n';
  return s.str();
}

// KITTI object pose of a car at (x, z) on the road (camera height 1.65 m: bottom at y = 1.65), yaw 0.
Eigen::Isometry3d carAt(double x, double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, 1.65, z);
  return T;
}

// The landmark pose (x fwd, y left, z up, centre) of a car of height h whose KITTI object pose is T.
Eigen::Isometry3d landmarkOf(const Eigen::Isometry3d& T_kobj, double h) {
  Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
  M.linear() << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  M.translation() = Eigen::Vector3d(0, -h / 2, 0);
  return T_kobj * M;
}

std::string objectEntry(int id, const Eigen::Isometry3d& T, const std::string& mesh) {
  std::ostringstream s;
  s.precision(12);
  s << "{\"track_id\": " << id << ", \"keyframes\": 4, \"T_world_obj\": [";
  for (int i = 0; i < 16; ++i) s << (i ? ", " : "") << T.matrix()(i / 4, i % 4);
  s << "], \"mesh\": " << (mesh.empty() ? "null" : "\"" + mesh + "\"") << "}";
  return s.str();
}

class ObjectScoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Truth: the camera drives along z at 1 m a frame. Car 1 parked at (3, 9), car 2 moving along z at
    // x = -3, car 3 parked 40 m ahead.
    std::string poses, times, objects_poses, motion = "# frame track moving speed\n", labels;
    for (int f = 0; f < 3; ++f) {
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.translation() = Eigen::Vector3d(0, 0, f);
      truth_cams_.push_back(T);
      poses += row34(T) + "\n";
      times += std::to_string(0.1 * f) + "\n";
      const Eigen::Isometry3d cars[3] = {carAt(3, 9), carAt(-3, 6 + 2 * f), carAt(0, 41)};
      for (int k = 0; k < 3; ++k) {
        objects_poses += std::to_string(f) + " " + std::to_string(k + 1) + " " + row34(cars[k]) + "\n";
        motion += std::to_string(f) + " " + std::to_string(k + 1) + (k == 1 ? " 1 20" : " 0 0") + "\n";
        const Eigen::Vector3d p_cam = cars[k].translation() - T.translation();
        std::ostringstream l;
        l << f << ' ' << k + 1 << " Car 0 0 0 100 100 200 200 1.5 1.8 4.5 " << p_cam.x() << ' ' << p_cam.y() << ' '
          << p_cam.z() << " 0\n";
        labels += l.str();
      }
    }
    dir_.write("data/poses/00.txt", poses);
    seq_ = dir_.path().string() + "/data/sequences/00";
    dir_.write("data/sequences/00/times.txt", times);
    dir_.write("data/sequences/00/objects/objects.txt",
               "# track_id type shape behaviour length width height\n1 Car sedan parked 4.5 1.8 1.5\n"
               "2 Car sedan driving 4.5 1.8 1.5\n3 Car sedan parked 4.5 1.8 1.5\n");
    dir_.write("data/sequences/00/objects/poses.txt", objects_poses);
    dir_.write("data/sequences/00/objects_motion.txt", motion);
    dir_.write("data/sequences/00/label_02/00.txt", labels);
    dir_.write("data/sequences/00/objects/car_0001.ply", boxPly(4.5, 1.8, 1.5, 0, true));
    // The run's world: the truth's turned 30 degrees about y and shifted.
    T_run_true_.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T_run_true_.translation() = Eigen::Vector3d(5, 0, -2);
    std::string trajectory;
    for (int f = 0; f < 3; ++f) trajectory += tum(0.1 * f, T_run_true_ * truth_cams_[f]);
    dir_.write("run/trajectory.tum", trajectory);
    dir_.write("run/summary.json", "{\"dataset_path\": \"" + seq_ + "\", \"dataset_sequence\": \"00\"}\n");
    // The reconstructed box mesh in the run's world, in the landmark frame of object 1 (centre origin).
    T_run_obj1_ = T_run_true_ * landmarkOf(carAt(3.3, 9), 1.5);
  }
  std::string run() const { return dir_.path().string() + "/run"; }
  // The mesh of object 1 in the run's world (the host writes meshes in the world frame).
  void writeObjectMesh() const {
    const Eigen::Isometry3d T = T_run_true_ * carAt(3.3, 9);  // KITTI object frame of the box mesh -> run world
    std::istringstream in(boxPly(4.5, 1.8, 1.5, 0));
    std::ostringstream out;
    std::string line;
    int vertex = -1;
    while (std::getline(in, line)) {
      if (vertex >= 0 && vertex < 8) {
        std::istringstream s(line);
        Eigen::Vector3d v;
        s >> v.x() >> v.y() >> v.z();
        const Eigen::Vector3d w = T * v;
        out << w.x() << ' ' << w.y() << ' ' << w.z() << '\n';
        ++vertex;
        continue;
      }
      out << line << '\n';
      if (line == "end_header") vertex = 0;
    }
    dir_.write("run/objects/object_0001.ply", out.str());
  }

  beslam::test::TempDir dir_;
  std::string seq_;
  std::vector<Eigen::Isometry3d> truth_cams_;
  Eigen::Isometry3d T_run_true_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_run_obj1_ = Eigen::Isometry3d::Identity();
};

TEST_F(ObjectScoreTest, CountsCorrectAndFalseObjectsThroughLocalAlignment) {
  writeObjectMesh();
  Eigen::Isometry3d nowhere = T_run_true_ * landmarkOf(carAt(-8, 4), 1.5);
  Eigen::Isometry3d on_moving = T_run_true_ * landmarkOf(carAt(-3, 8), 1.5);
  dir_.write("run/objects.json", "{\"objects\": [" + objectEntry(1, T_run_obj1_, "objects/object_0001.ply") + ", " +
                                     objectEntry(2, on_moving, "") + ", " + objectEntry(7, nowhere, "") + "]}\n");
  const auto s = score(run(), Options{});
  EXPECT_EQ(s.reconstructed, 3);
  EXPECT_EQ(s.correct, 1);
  EXPECT_EQ(s.false_objects, 2);   // the moving car and no car
  EXPECT_EQ(s.parked_in_view, 1);  // car 3 is 38-41 m away
  EXPECT_EQ(s.parked_in_view_correct, 1);
  ASSERT_EQ(s.objects.size(), 3u);
  EXPECT_EQ(s.objects[0].truth_track_id, 1);
  EXPECT_NEAR(s.objects[0].centre_error_m, 0.3, 1e-6);
  EXPECT_NEAR(s.objects[0].yaw_error_deg, 0.0, 1e-6);
  // (0.052 m from sampling alone; 0.092 m when the buried box's faces count)
  EXPECT_NEAR(s.objects[0].shape_chamfer_m, 0.0, 0.07);                    // the same box, sampled independently
  EXPECT_GT(s.objects[0].chamfer_m, s.objects[0].shape_chamfer_m + 0.02);  // the 0.3 m offset shows
  EXPECT_LT(s.objects[0].chamfer_m, 0.35);
  EXPECT_TRUE(s.objects[1].moving);
  EXPECT_EQ(s.objects[2].truth_track_id, -1);
}

TEST_F(ObjectScoreTest, AWrongHeadingIsNotCorrect) {
  Eigen::Isometry3d turned = T_run_obj1_;
  turned.linear() = turned.linear() * Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  dir_.write("run/objects.json", "{\"objects\": [" + objectEntry(1, turned, "") + "]}\n");
  const auto s = score(run(), Options{});
  EXPECT_EQ(s.correct, 0);
  EXPECT_NEAR(s.objects[0].yaw_error_deg, 0.6 * 180 / M_PI, 1e-6);
  EXPECT_EQ(s.parked_in_view_correct, 0);
}

TEST_F(ObjectScoreTest, BadInputIsOneErrorNamingTheFile) {
  auto message = [&] {
    try {
      score(run(), Options{});
    } catch (const beslam::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message().find("objects.json: cannot open"), std::string::npos) << message();
  dir_.write("run/objects.json", "{\"objects\": [{\"track_id\": 1, \"T_world_obj\": [1, 2]}]}");
  EXPECT_NE(message().find("objects.json: object 0: T_world_obj has 2 numbers"), std::string::npos) << message();
  dir_.write("run/objects.json", "{\"objects\": [" + objectEntry(1, T_run_obj1_, "objects/missing.ply") + "]}");
  EXPECT_NE(message().find("missing.ply: cannot open"), std::string::npos) << message();
  dir_.write("run/objects.json", "[1, 2");
  EXPECT_NE(message().find("objects.json: not JSON"), std::string::npos) << message();
  dir_.write("run/summary.json", "{}");
  EXPECT_NE(message().find("summary.json: no dataset_path"), std::string::npos) << message();
}

TEST_F(ObjectScoreTest, CommandPrintsTheCountsAndRefusesUsageErrors) {
  dir_.write("run/objects.json", "{\"objects\": [" + objectEntry(1, T_run_obj1_, "") + "]}\n");
  std::ostringstream out, err;
  EXPECT_EQ(beslam::object_score::runCommand({"--run", run()}, out, err), 0) << err.str();
  EXPECT_NE(out.str().find("correctly reconstructed 1 of 1"), std::string::npos) << out.str();
  EXPECT_EQ(beslam::object_score::runCommand({"--bogus"}, out, err), 2);
  EXPECT_EQ(beslam::object_score::runCommand({"--run", dir_.path().string() + "/nothing"}, out, err), 1);
}

}  // namespace
