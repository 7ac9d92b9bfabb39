// reconstructor_sdf: the paper's Algorithm 2 with a shape prior the project learns itself. On each
// keyframe of a metric world: parked cars (boxes the motion checker calls static, by track id) collect
// observations (objects/object_store.hpp: LiDAR returns in the box when the frame has a scan, else the
// backend's map points labelled on the car, with rays through the car's mask and the background beside
// it, objects/mask_silhouettes.hpp), kept with their keyframes and moved as the backend moves those (ABI
// 1.6 keyframe poses); each car seen again is refitted (fit/object_fit.hpp: pose, shape code, optionally
// size, from the box consensus or the last fit) and returned as a landmark with surface samples and a
// mesh; a car called dynamic is returned as removed. finish() refits every object once with all it
// gathered. docs/reconstruction.md describes the prior, the energy and the settings.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <opencv2/core/utility.hpp>
#include <optional>
#include <string>
#include <utility>

#include "beslam/sdk/sdk.hpp"
#include "fit/object_fit.hpp"
#include "objects/mask_silhouettes.hpp"
#include "objects/object_store.hpp"
#include "reconstructor_sdf_settings.hpp"  // Options and kSettings, from settings.json
#include "shape/mesh.hpp"
#include "shape/shape_prior.hpp"

namespace {

namespace recon = beslam::recon;

const beslam::sdk::PluginInfo kInfo("reconstructor_sdf", "SDF shape-prior reconstructor",
                                    "Parked cars as shape-and-pose landmarks: a learnt PCA signed-distance prior "
                                    "fitted to LiDAR returns or map points (Algorithm 2)",
                                    {1, 0, 0}, kSettings);

Options readOptions(const beslam::sdk::Config& config) {
  Options o = kSettings.read(config);
  o.fit.box_sigma_yaw = o.box_sigma_yaw_deg * M_PI / 180.0;
  return o;
}

std::string resolvePrior(const std::string& setting) {
  if (!setting.empty()) return setting;
  for (const char* candidate : {BESLAM_SHAPE_PRIOR_INSTALLED, BESLAM_SHAPE_PRIOR_SOURCE}) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(candidate, ec)) return candidate;
  }
  throw beslam::sdk::ConfigError("prior: no shape prior found (looked for " +
                                 std::string(BESLAM_SHAPE_PRIOR_INSTALLED) + " and " + BESLAM_SHAPE_PRIOR_SOURCE +
                                 "); set reconstructor.prior");
}

// An object's last fit and where its boxes' consensus was then (a later refit starts from the fit shifted as
// the consensus moved with its keyframes).
struct LastFit {
  recon::fit::FitResult result;
  Eigen::Isometry3d T_world_boxes;
};

class SdfReconstructor : public beslam::sdk::Reconstructor {
 public:
  SdfReconstructor(const beslam::sdk::Context& context, const beslam::sdk::Config& config)
      : context_(context),
        options_(readOptions(config)),
        prior_(recon::shape::ShapePrior::load(resolvePrior(options_.prior))),
        store_(options_.store) {}

  std::vector<beslam::sdk::Landmark> reconstruct(const beslam::sdk::Keyframe& keyframe, const beslam::sdk::Frame& frame,
                                                 const std::vector<beslam_box3d>& boxes, const cv::Mat& mask) override {
    recon::KeyframeInput input;
    input.keyframe_id = keyframe.id;
    input.frame_index = keyframe.frame_index;
    input.T_world_cam = keyframe.T_world_cam;
    input.boxes = &boxes;
    for (const beslam::sdk::KeyframePoint& p : keyframe.points) input.points.push_back({p.id, p.p_world, p.label});
    if (frame.hasLidar() && context_.T_cam_lidar()) {
      const auto scan = frame.lidarPoints();
      input.lidar_cam.reserve(scan.cols());
      for (Eigen::Index i = 0; i < scan.cols(); ++i) {
        const Eigen::Vector3d p_cam = *context_.T_cam_lidar() * scan.col(i).head<3>().cast<double>();
        if (p_cam.allFinite()) input.lidar_cam.push_back(p_cam);
      }
    }
    if (options_.silhouette_grid > 0)
      input.silhouettes = recon::sampleSilhouettes(mask, context_.camera(), boxes, options_.silhouette_grid);
    store_.followKeyframes(keyframe.T_world_cam_by_frame);
    std::vector<int32_t> ended;
    const std::set<int32_t> updated = store_.observe(input, ended);
    std::vector<beslam::sdk::Landmark> out;
    for (int32_t id : ended) {
      fits_.erase(id);
      beslam::sdk::Landmark l;
      l.track_id = id;
      l.removed = true;
      out.push_back(std::move(l));
    }
    std::vector<const recon::ObjectRecord*> records;
    for (int32_t id : updated) {
      records.push_back(store_.find(id));
      if (std::getenv("BESLAM_RECON_DEBUG"))
        std::fprintf(stderr, "kf %ld frame %ld: object %d boxes %zu points %zu lidar %zu (kf points %zu)\n",
                     static_cast<long>(keyframe.id), static_cast<long>(keyframe.frame_index), id,
                     records.back()->boxes.size(), records.back()->map_points.size(), records.back()->lidarPointCount(),
                     keyframe.points.size());
    }
    refitAll(records, out);
    return out;
  }

  std::vector<beslam::sdk::Landmark> finish() override {
    std::vector<beslam::sdk::Landmark> out;
    std::vector<const recon::ObjectRecord*> records;
    for (const auto& [id, record] : store_.objects()) records.push_back(&record);
    refitAll(records, out);
    return out;
  }

 private:
  // Refits the objects on OpenCV's thread pool (each fit reads only its own record and last fit), then
  // keeps the results in the objects' order: the same landmarks whatever the threads.
  void refitAll(const std::vector<const recon::ObjectRecord*>& records, std::vector<beslam::sdk::Landmark>& out) {
    std::vector<std::optional<std::pair<LastFit, beslam::sdk::Landmark>>> fitted(records.size());
    std::vector<std::string> why(records.size());
    cv::parallel_for_(cv::Range(0, static_cast<int>(records.size())), [&](const cv::Range& range) {
      for (int i = range.start; i < range.end; ++i) fitted[i] = refit(*records[i], why[i]);
    });
    for (size_t i = 0; i < records.size(); ++i)
      if (!why[i].empty()) {
        context_.log(BESLAM_LOG_DEBUG, "object " + std::to_string(records[i]->track_id) + " not fitted: " + why[i]);
      } else if (fitted[i]) {
        fits_[records[i]->track_id] = std::move(fitted[i]->first);
        out.push_back(std::move(fitted[i]->second));
      }
  }

  // Fits one object from its observations (starting from its last fit, else from its boxes); nothing
  // when it has too few observations or the fit fails (why: the fit's reason; the object waits for more
  // keyframes).
  std::optional<std::pair<LastFit, beslam::sdk::Landmark>> refit(const recon::ObjectRecord& record,
                                                                 std::string& why) const {
    recon::fit::FitObservations obs;
    obs.p_world = record.surfaceObservations(options_.store.map_point_margin);
    const Eigen::Isometry3d T_world_boxes = record.boxPose();
    obs.T_world_obj_boxes = T_world_boxes;
    const bool lidar = record.lidarPointCount() > 0;
    // Silhouettes where the car has no LiDAR returns: returns of 3 cm leave nothing for an outline of
    // decimetres to add (measured: the same fits at a quarter more cost, docs/reconstruction.md).
    if (!lidar)
      for (const recon::WorldSilhouetteRay& ray : record.silhouetteRays())
        obs.silhouette.push_back({ray.origin_world, ray.direction_world, ray.inside, 1.0});
    // Enough surface observations, or silhouettes from enough keyframes: a car the map has too few points
    // on is still placed and shaped by its outline in several views.
    const bool enough_points =
        static_cast<int>(obs.p_world.size()) >= (lidar ? options_.min_lidar_points : options_.min_map_points);
    const bool enough_silhouettes = !lidar && options_.silhouette_grid > 0 && options_.min_silhouette_keyframes > 0 &&
                                    static_cast<int>(record.silhouettes.size()) >= options_.min_silhouette_keyframes;
    if (!enough_points && !enough_silhouettes) return std::nullopt;
    recon::fit::FitOptions fit = options_.fit;
    if (!lidar)
      fit.sigma_m = options_.map_sigma_m, fit.huber_m = options_.map_huber_m, fit.inlier_m = options_.map_huber_m;
    // From the last fit, shifted as its boxes' consensus moved since (keyframes corrected, new boxes); the
    // heading stays the fit's (a consensus may flip front and back).
    const auto last = fits_.find(record.track_id);
    Eigen::Isometry3d T_init = T_world_boxes;
    if (last != fits_.end()) {
      T_init = last->second.result.T_world_obj;
      T_init.translation() += T_world_boxes.translation() - last->second.T_world_boxes.translation();
    }
    const Eigen::Vector3d size = last != fits_.end() ? last->second.result.size : record.boxSize();
    const Eigen::VectorXd code =
        last != fits_.end() ? last->second.result.code : Eigen::VectorXd::Zero(prior_.dimensions());
    recon::fit::FitResult r = recon::fit::fitObject(prior_, T_init, size, code, obs, fit);
    if (!r.ok) {
      why = r.why.empty() ? "fit failed" : r.why;
      return std::nullopt;
    }
    beslam::sdk::Landmark l;
    l.track_id = record.track_id;
    l.class_id = record.class_id;
    l.T_world_object = r.T_world_obj;
    l.scale = r.size;
    l.shape_code.assign(r.code.data(), r.code.data() + r.code.size());
    l.keyframes = static_cast<int32_t>(record.boxes.size());
    l.cost = r.cost;
    // Confidence: the share of observations on the fitted surface (without any, of silhouette rays on their
    // side of it).
    if (!obs.p_world.empty())
      l.confidence = static_cast<float>(double(r.inliers) / double(obs.p_world.size()));
    else if (!obs.silhouette.empty())
      l.confidence = static_cast<float>(double(r.silhouette_agree) / double(obs.silhouette.size()));
    // One mesh for both: the surface samples are drawn from it (as ShapePrior::surfaceSamples does).
    const recon::shape::Mesh mesh = prior_.mesh(r.code, r.size);
    for (const Eigen::Vector3d& p :
         recon::shape::surfaceSamples(mesh, options_.surface_samples, recon::shape::ShapePrior::kSurfaceSampleSeed))
      l.surface_points.insert(l.surface_points.end(), {float(p.x()), float(p.y()), float(p.z())});
    if (options_.meshes) {
      for (const auto& v : mesh.vertices)
        l.mesh_vertices.insert(l.mesh_vertices.end(), {float(v.x()), float(v.y()), float(v.z())});
      for (const auto& f : mesh.faces)
        l.mesh_faces.insert(l.mesh_faces.end(), {uint32_t(f[0]), uint32_t(f[1]), uint32_t(f[2])});
    }
    return std::make_pair(LastFit{std::move(r), T_world_boxes}, std::move(l));
  }

  const beslam::sdk::Context& context_;
  Options options_;
  recon::shape::ShapePrior prior_;
  recon::ObjectStore store_;
  std::map<int32_t, LastFit> fits_;
};

}  // namespace

BESLAM_EXPORT_PLUGINS(beslam::sdk::describe<SdfReconstructor>(kInfo))
