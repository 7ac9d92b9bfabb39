#include "beslam/detector_replay/nuscenes.hpp"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

namespace beslam::detector_replay {

namespace {

using json = nlohmann::json;

json loadJson(const std::string& path, const char* what) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open " + what);
  try {
    return json::parse(in);
  } catch (const json::parse_error& e) {
    // e.byte is the offset of the error: turn it into a line number.
    std::ifstream again(path);
    std::string text((std::istreambuf_iterator<char>(again)), std::istreambuf_iterator<char>());
    int line = 1;
    for (size_t i = 0; i < text.size() && i + 1 < e.byte; ++i) line += text[i] == '\n';
    throw std::runtime_error(path + ":" + std::to_string(line) + ": JSON syntax error: " + e.what());
  } catch (const json::exception& e) {  // e.g. a number past double's range (out_of_range 406)
    throw std::runtime_error(path + ": JSON error: " + e.what());
  }
}

std::vector<double> numbers(const json& j, size_t n, const std::string& what) {
  if (!j.is_array() || j.size() != n)
    throw std::runtime_error(what + ": expected an array of " + std::to_string(n) + " numbers");
  std::vector<double> v;
  for (const auto& x : j) {
    if (!x.is_number()) throw std::runtime_error(what + ": '" + x.dump() + "' is not a number");
    const double d = x.get<double>();
    if (!std::isfinite(d)) throw std::runtime_error(what + ": non-finite value");
    v.push_back(d);
  }
  return v;
}

NuScenesBox parseBox(const json& j, const std::string& where) {
  if (!j.is_object()) throw std::runtime_error(where + ": expected a box object");
  auto field = [&](const char* key) -> const json& {
    auto it = j.find(key);
    if (it == j.end()) throw std::runtime_error(where + ": missing '" + key + "'");
    return *it;
  };
  NuScenesBox b;
  const auto t = numbers(field("translation"), 3, where + ": translation");
  b.translation = Eigen::Vector3d(t[0], t[1], t[2]);
  const auto s = numbers(field("size"), 3, where + ": size");
  if (!(s[0] > 0 && s[1] > 0 && s[2] > 0)) throw std::runtime_error(where + ": size (w l h) must be positive");
  b.size_wlh = Eigen::Vector3d(s[0], s[1], s[2]);
  const auto q = numbers(field("rotation"), 4, where + ": rotation");
  const Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
  if (quat.norm() < 1e-6) throw std::runtime_error(where + ": rotation is a zero quaternion");
  b.rotation = quat.normalized();
  if (auto it = j.find("velocity"); it != j.end() && !it->is_null()) {
    // Some writers put NaN (as null or a string) where the velocity is unknown: treat as absent.
    bool unknown = it->is_array() && !it->empty();
    for (const auto& x : *it) unknown = unknown && (x.is_null() || x.is_string());
    if (!unknown) {
      if (!it->is_array() || (it->size() != 2 && it->size() != 3))
        throw std::runtime_error(where + ": velocity: expected [vx, vy]");
      const auto v = numbers(*it, it->size(), where + ": velocity");
      b.velocity = Eigen::Vector2d(v[0], v[1]);
    }
  }
  const json& name = field("detection_name");
  if (!name.is_string()) throw std::runtime_error(where + ": detection_name is not a string");
  b.name = name.get<std::string>();
  const json& score = field("detection_score");
  if (!score.is_number() || !std::isfinite(score.get<double>()))
    throw std::runtime_error(where + ": detection_score is not a finite number");
  b.score = score.get<double>();
  return b;
}

}  // namespace

Eigen::Isometry3d poseFromTranslationQuaternion(const std::vector<double>& v, const std::string& what) {
  if (v.size() != 7) throw std::invalid_argument(what + ": expected 7 numbers: tx ty tz qw qx qy qz");
  const Eigen::Quaterniond q(v[3], v[4], v[5], v[6]);
  if (q.norm() < 1e-6) throw std::invalid_argument(what + ": zero quaternion");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return T;
}

beslam_box3d cameraFromGlobal(const NuScenesBox& box, int32_t class_id, const Eigen::Isometry3d& T_cam_global) {
  beslam_box3d b{};
  b.class_id = class_id;
  b.track_id = -1;
  b.motion_state = BESLAM_MOTION_UNKNOWN;
  const Eigen::Vector3d c = T_cam_global * box.translation;
  for (int k = 0; k < 3; ++k) b.center_cam[k] = c[k];
  b.size[0] = box.size_wlh[1];  // length
  b.size[1] = box.size_wlh[0];  // width
  b.size[2] = box.size_wlh[2];  // height
  const Eigen::Vector3d heading = T_cam_global.linear() * (box.rotation * Eigen::Vector3d::UnitX());
  b.yaw = std::atan2(-heading.z(), heading.x());
  if (box.velocity) {
    const Eigen::Vector3d v = T_cam_global.linear() * Eigen::Vector3d(box.velocity->x(), box.velocity->y(), 0.0);
    for (int k = 0; k < 3; ++k) b.velocity_cam[k] = v[k];
    b.flags |= BESLAM_BOX_HAS_VELOCITY;
  }
  b.score = static_cast<float>(box.score);
  return b;
}

NuScenesBox globalFromCamera(const beslam_box3d& b, const Eigen::Isometry3d& T_cam_global) {
  const Eigen::Isometry3d T_global_cam = T_cam_global.inverse();
  NuScenesBox out;
  out.translation = T_global_cam * Eigen::Vector3d(b.center_cam[0], b.center_cam[1], b.center_cam[2]);
  out.size_wlh = Eigen::Vector3d(b.size[1], b.size[0], b.size[2]);
  const Eigen::Vector3d heading_cam(std::cos(b.yaw), 0.0, -std::sin(b.yaw));
  const Eigen::Vector3d h = T_global_cam.linear() * heading_cam;
  out.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(std::atan2(h.y(), h.x()), Eigen::Vector3d::UnitZ()));
  if (b.flags & BESLAM_BOX_HAS_VELOCITY) {
    const Eigen::Vector3d v =
        T_global_cam.linear() * Eigen::Vector3d(b.velocity_cam[0], b.velocity_cam[1], b.velocity_cam[2]);
    out.velocity = v.head<2>();
  }
  out.score = b.score;
  return out;
}

NuScenesFrames readNuScenesFrames(const std::string& path) {
  NuScenesFrames f;
  const bool is_json = path.size() >= 5 && path.compare(path.size() - 5, 5, ".json") == 0;
  if (!is_json) {
    forEachLine(path, "sample token file", [&](const std::string& line, int line_no) {
      const auto a = line.find_first_not_of(" \t");
      if (a == std::string::npos || line[a] == '#') return;
      const auto b = line.find_last_not_of(" \t");
      const std::string token = line.substr(a, b - a + 1);
      if (token.find_first_of(" \t") != std::string::npos)
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": expected one sample token, got '" + token +
                                 "'");
      f.tokens.push_back(token);
      f.T_global_ego.emplace_back();
    });
  } else {
    json j = loadJson(path, "sample token file");
    if (j.is_object() && j.contains("frames")) j = j["frames"];
    if (!j.is_array()) throw std::runtime_error(path + ": expected an array of sample tokens (or {\"frames\": [...]})");
    for (size_t i = 0; i < j.size(); ++i) {
      const json& e = j[i];
      const std::string where = path + ": frame " + std::to_string(i);
      if (e.is_string()) {
        f.tokens.push_back(e.get<std::string>());
        f.T_global_ego.emplace_back();
        continue;
      }
      if (!e.is_object() || !e.contains("token") || !e["token"].is_string())
        throw std::runtime_error(where + ": expected a token string or an object with \"token\"");
      f.tokens.push_back(e["token"].get<std::string>());
      if (e.contains("ego_translation") || e.contains("ego_rotation")) {
        if (!e.contains("ego_translation") || !e.contains("ego_rotation"))
          throw std::runtime_error(where + ": ego_translation and ego_rotation go together");
        std::vector<double> v = numbers(e["ego_translation"], 3, where + ": ego_translation");
        const std::vector<double> q = numbers(e["ego_rotation"], 4, where + ": ego_rotation");
        v.insert(v.end(), q.begin(), q.end());
        try {
          f.T_global_ego.emplace_back(poseFromTranslationQuaternion(v, where));
        } catch (const std::invalid_argument& ex) {
          throw std::runtime_error(ex.what());
        }
      } else {
        f.T_global_ego.emplace_back();
      }
    }
  }
  if (f.tokens.empty()) throw std::runtime_error(path + ": no sample tokens");
  return f;
}

void readNuScenes(const NuScenesOptions& o, DetectionTable& table, std::vector<char>& covered, Report& report) {
  const json root = loadJson(o.results, "detection results");
  if (!root.is_object() || !root.contains("results") || !root["results"].is_object())
    throw std::runtime_error(o.results + ": expected a nuScenes results object with a \"results\" map");
  const json& results = root["results"];
  const size_t n = o.frames.tokens.size();
  covered.assign(n, 0);
  const Eigen::Isometry3d T_cam_ego = o.T_ego_cam.inverse();
  for (size_t i = 0; i < n; ++i) {
    const std::string& token = o.frames.tokens[i];
    auto it = results.find(token);
    if (it == results.end()) continue;  // missing frame: the caller's policy
    std::optional<Eigen::Isometry3d> T_global_ego;
    if (i < o.ego_poses.size())
      T_global_ego = o.ego_poses[i];
    else if (o.frames.T_global_ego[i])
      T_global_ego = o.frames.T_global_ego[i];
    if (!T_global_ego) continue;
    const Eigen::Isometry3d T_cam_global = T_cam_ego * T_global_ego->inverse();
    if (!it->is_array()) throw std::runtime_error(o.results + ": sample " + token + ": expected a list of boxes");
    covered[i] = 1;
    table.cover(static_cast<int64_t>(i));
    for (size_t k = 0; k < it->size(); ++k) {
      ++report.rows;
      const std::string where = o.results + ": sample " + token + ", box " + std::to_string(k);
      try {
        const NuScenesBox box = parseBox((*it)[k], where);
        int32_t class_id = 0;
        if (!nuscenesClass(box.name, class_id))
          throw std::runtime_error(where + ": unknown detection_name '" + box.name + "'");
        const beslam_box3d b = cameraFromGlobal(box, class_id, T_cam_global);
        if (!o.filter.keeps(b)) {
          ++report.filtered;
          continue;
        }
        table.add(static_cast<int64_t>(i), b);
        ++report.boxes;
      } catch (const std::exception& e) {
        if (o.policy == Policy::stop) throw std::runtime_error(e.what());
        ++report.skipped;
        report.problem(e.what());
      }
    }
  }
}

}  // namespace beslam::detector_replay
