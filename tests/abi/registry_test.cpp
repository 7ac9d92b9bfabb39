// The host against good and deliberately broken plugin libraries: every refusal names the file and the
// cause, and no exception from a plugin crosses the C ABI.
#include "beslam/registry/registry.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>

#include "beslam/common/error.hpp"
#include "beslam/registry/instance.hpp"

using beslam::registry::Registry;

namespace {

std::string fixture(const std::string& name) { return std::string(FIXTURE_DIR) + "/" + name + ".so"; }

// Loads a library expecting a refusal; returns the message.
std::string refusal(const std::string& path) {
  Registry registry;
  try {
    registry.loadLibrary(path);
  } catch (const beslam::Error& e) {
    return e.what();
  }
  ADD_FAILURE() << path << " was accepted";
  return {};
}

// The message of the beslam::Error that f throws (a failure when it throws none).
std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const beslam::Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no beslam::Error thrown";
  return {};
}

// Loads a library expecting a refusal whose message contains every one of `parts`.
void expectRefusal(const std::string& path, std::initializer_list<const char*> parts) {
  const std::string message = refusal(path);
  for (const char* part : parts) EXPECT_NE(message.find(part), std::string::npos) << message;
}

beslam_create_info createInfo(const beslam::registry::HostLog& log, const std::vector<beslam_config_value>& config) {
  beslam_create_info info{};
  info.struct_size = sizeof(info);
  info.host = log.host();
  info.config = config.data();
  info.config_count = static_cast<uint32_t>(config.size());
  info.camera = {sizeof(beslam_camera), 64, 48, 0, 50, 50, 32, 24};
  return info;
}

// A frame with nothing but its struct size set.
beslam_frame emptyFrame() {
  beslam_frame frame{};
  frame.struct_size = sizeof(frame);
  return frame;
}

// A host with fixture libraries loaded: its registry, and the log its plugin instances write to.
struct FixtureHost {
  Registry registry;
  beslam::registry::HostLog log;

  explicit FixtureHost(std::initializer_list<const char*> libraries) {
    for (const char* name : libraries) registry.loadLibrary(fixture(name));
  }
  // The plugin `id` created as an I (DetectorInstance, BackendInstance, ...) with `config`.
  template <class I>
  I create(const std::string& id, const std::vector<beslam_config_value>& config = {}) {
    return I(registry.find(id), createInfo(log, config), log);
  }
};

beslam_config_value number(const char* key, int32_t type, double v) {
  beslam_config_value c{};
  c.key = key;
  c.type = type;
  c.number = v;
  return c;
}

// The error creating the detector `plugin` of the SDK fixtures with `config` (a failure when it is created).
std::string createError(const std::string& plugin, const std::vector<beslam_config_value>& config) {
  FixtureHost host({"sdk_fixtures"});
  return errorOf([&] { auto d = host.create<beslam::registry::DetectorInstance>(plugin, config); });
}

}  // namespace

TEST(Registry, RefusesWrongMajorVersion) {
  expectRefusal(fixture("wrong_major"), {"wrong_major.so", "ABI 2.0", "major versions must match"});
}

TEST(Registry, RefusesShortDescriptor) {
  expectRefusal(fixture("short_struct"), {"short_struct.so", "struct_size 16"});
}

TEST(Registry, RefusesMissingEntryPoint) {
  expectRefusal(fixture("missing_function"), {"missing_function.so", "missing symbol beslam_plugin_list"});
}

TEST(Registry, RefusesLibraryThatIsNotAPlugin) { expectRefusal(fixture("not_a_plugin"), {"not a BE-SLAM plugin"}); }

TEST(Registry, RefusesNullFunctionInTable) {
  expectRefusal(fixture("null_function"), {"null_function.so", "function of its table is null"});
}

TEST(Registry, RefusesMissingFileAndNonLibrary) {
  EXPECT_NE(refusal("/nonexistent/plugin.so").find("no such plugin library"), std::string::npos);
  const std::string text = std::string(FIXTURE_DIR) + "/../abi_text_file.so";
  {
    FILE* f = std::fopen(text.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("not an ELF file", f);
    std::fclose(f);
  }
  const std::string message = refusal(text);
  EXPECT_NE(message.find("abi_text_file.so: not a shared library (no ELF header"), std::string::npos) << message;
}

TEST(Registry, ScanCollectsProblemsAndKeepsGoodPlugins) {
  Registry registry;
  registry.addSearchPath(FIXTURE_DIR);
  registry.scan();
  EXPECT_EQ(registry.problems().size(), 5u);
  EXPECT_NO_THROW(registry.find("fixture_boxes", BESLAM_KIND_DETECTOR));
  EXPECT_NE(errorOf([&] { registry.find("fixture_boxes", BESLAM_KIND_BACKEND); }).find("is a detector, not a backend"),
            std::string::npos);
  const std::string unknown = errorOf([&] { registry.find("no_such_plugin", BESLAM_KIND_DETECTOR); });
  EXPECT_NE(unknown.find("known: detector_1_4, fixture_throwing, fixture_boxes"), std::string::npos) << unknown;
}

TEST(Registry, ListsSchemaOfSdkPlugin) {
  Registry registry;
  registry.loadLibrary(fixture("sdk_fixtures"));
  const auto& p = registry.find("fixture_boxes");
  EXPECT_EQ(p.version, "0.1.0");
  ASSERT_EQ(p.fields.size(), 6u);
  EXPECT_EQ(p.fields[1].key, "depth");
  EXPECT_EQ(p.fields[1].type, BESLAM_CONFIG_DOUBLE);
  EXPECT_DOUBLE_EQ(p.fields[1].min_value, 0.5);
  EXPECT_EQ(p.fields[3].choices, "car|pedestrian");
}

TEST(Registry, ExceptionInCreateBecomesAnErrorWithItsMessage) {
  const std::string m = createError("fixture_throwing", {});
  EXPECT_NE(m.find("fixture_throwing"), std::string::npos) << m;
  EXPECT_NE(m.find("create failed (runtime error): constructor exploded on purpose"), std::string::npos) << m;
}

TEST(Registry, MissingConfigValueIsInvalidConfig) {
  const std::string m = createError("fixture_boxes", {number("emit_nan", BESLAM_CONFIG_BOOL, 0)});
  EXPECT_NE(m.find("invalid configuration"), std::string::npos) << m;
  EXPECT_NE(m.find("'depth' is missing"), std::string::npos) << m;
}

TEST(Registry, DetectAndClassifyRoundTrip) {
  FixtureHost host({"sdk_fixtures"});
  const double size[] = {4.0, 1.8, 1.5};
  beslam_config_value list{};
  list.key = "size";
  list.type = BESLAM_CONFIG_DOUBLE_LIST;
  list.list = size;
  list.list_size = 3;
  beslam_config_value cls{};
  cls.key = "class_name";
  cls.type = BESLAM_CONFIG_STRING;
  cls.text = "car";
  const std::vector<beslam_config_value> config = {number("emit_nan", BESLAM_CONFIG_BOOL, 0),
                                                   number("depth", BESLAM_CONFIG_DOUBLE, 12.5),
                                                   number("count", BESLAM_CONFIG_INT, 3),
                                                   cls,
                                                   list,
                                                   number("range_sigma", BESLAM_CONFIG_DOUBLE, 0)};
  auto detector = host.create<beslam::registry::DetectorInstance>("fixture_boxes", config);
  auto checker = host.create<beslam::registry::MotionCheckerInstance>("fixture_all_static",
                                                                      {number("corrupt_nan", BESLAM_CONFIG_BOOL, 0)});

  std::vector<uint8_t> pixels(64 * 48, 128);
  beslam_frame frame = emptyFrame();
  frame.gray = {pixels.data(), 64, 48, 64, BESLAM_PIXEL_GRAY8};
  std::vector<beslam_box3d> boxes = detector.detect(frame);
  ASSERT_EQ(boxes.size(), 3u);
  EXPECT_DOUBLE_EQ(boxes[0].center_cam[2], 12.5);
  EXPECT_EQ(boxes[0].track_id, -1);
  EXPECT_DOUBLE_EQ(boxes[2].size[1], 1.8);

  checker.classify(frame, Eigen::Isometry3d::Identity(), boxes);
  EXPECT_EQ(boxes[1].track_id, 8);
  EXPECT_EQ(boxes[1].motion_state, BESLAM_MOTION_STATIC);
  checker.classify(frame, std::nullopt, boxes);
  EXPECT_EQ(boxes[1].motion_state, BESLAM_MOTION_UNKNOWN);

  // An exception inside a call becomes a status and a message, never a crash.
  beslam_frame empty = emptyFrame();
  const std::string m = errorOf([&] { detector.detect(empty); });
  EXPECT_NE(m.find("detect failed (invalid argument): frame without a grey image"), std::string::npos) << m;
}

TEST(Registry, LandmarksCrossTheAbiWithMeshesPointsAndRemovals) {
  FixtureHost host({"sdk_fixtures"});
  auto reconstructor = host.create<beslam::registry::ReconstructorInstance>("fixture_box_objects");
  std::vector<uint8_t> pixels(64 * 48, 128);
  beslam_frame frame = emptyFrame();
  frame.gray = {pixels.data(), 64, 48, 64, BESLAM_PIXEL_GRAY8};
  beslam_box3d box{};
  box.class_id = BESLAM_CLASS_CAR;
  box.track_id = 4;
  box.motion_state = BESLAM_MOTION_STATIC;
  box.center_cam[2] = 10;
  box.size[0] = 4, box.size[1] = 2, box.size[2] = 1.5;
  std::vector<beslam_keyframe_point> points(3);
  points[0].label = BESLAM_LABEL_STATIC_BASE + 4;
  points[1].label = BESLAM_LABEL_STATIC_BASE + 4;
  points[2].label = BESLAM_LABEL_BACKGROUND;
  beslam_keyframe kf{};
  kf.struct_size = sizeof(kf);
  kf.world_scale = BESLAM_WORLD_SCALE_METRIC;
  for (int i = 0; i < 3; ++i) kf.T_world_cam.m[i * 5] = 1;
  kf.T_world_cam.m[3] = 2;  // the camera 2 m along world x
  kf.points = points.data();
  kf.point_count = 3;
  kf.point_size = sizeof(beslam_keyframe_point);
  const beslam_image_view no_mask{};
  beslam::registry::Landmarks made = reconstructor.reconstruct(kf, frame, {box}, no_mask);
  ASSERT_EQ(made.size(), 1u);
  EXPECT_EQ(made[0].track_id, 4);
  EXPECT_EQ(made[0].keyframes, 2);  // the two keyframe points on object 4 reached the plugin
  EXPECT_NEAR(made[0].T_world_object.translation().x(), 2, 1e-12);
  EXPECT_NEAR(made[0].T_world_object.translation().z(), 10, 1e-12);
  EXPECT_EQ(made[0].mesh_vertices.size(), 24u);
  EXPECT_EQ(made[0].mesh_faces.size(), 36u);
  EXPECT_FALSE(made[0].removed);
  EXPECT_EQ(made[0].cost, 0.0) << "no keyframe poses given, none seen";
  {
    // ABI 1.6: the backend's keyframe poses reach the plugin, read at the host's element size; a keyframe
    // struct of an ABI 1.5 host (152 bytes) ends before them and the plugin sees none.
    std::vector<beslam_trajectory_entry> poses(2);
    for (beslam_trajectory_entry& e : poses)
      for (int i = 0; i < 3; ++i) e.T_world_cam.m[i * 5] = 1;
    poses[0].frame_index = 3, poses[0].T_world_cam.m[3] = 7;
    poses[1].frame_index = 9;
    beslam_keyframe with_poses = kf;
    with_poses.keyframe_poses = poses.data();
    with_poses.keyframe_pose_count = 2;
    with_poses.keyframe_pose_size = sizeof(beslam_trajectory_entry);
    EXPECT_DOUBLE_EQ(reconstructor.reconstruct(with_poses, frame, {box}, no_mask)[0].cost, 2.007);
    with_poses.struct_size = 152;
    EXPECT_EQ(reconstructor.reconstruct(with_poses, frame, {box}, no_mask)[0].cost, 0.0);
  }
  // The host's copy owns its arrays: it outlives the plugin's next call.
  const beslam::registry::Landmarks first = made;
  box.motion_state = BESLAM_MOTION_DYNAMIC;
  made = reconstructor.reconstruct(kf, frame, {box}, no_mask);
  ASSERT_EQ(made.size(), 1u);
  EXPECT_TRUE(made[0].removed);
  EXPECT_FLOAT_EQ(first[0].mesh_vertices[0], -2.0f);
  EXPECT_TRUE(reconstructor.finish().empty());  // nothing left: object 4 was removed
}

TEST(Registry, AnAbi12ReconstructorStillLoadsAndItsLandmarksRead) {
  FixtureHost host({"reconstructor_1_2"});
  auto reconstructor = host.create<beslam::registry::ReconstructorInstance>("reconstructor_1_2");
  beslam_frame frame = emptyFrame();
  beslam_keyframe kf{};
  kf.struct_size = sizeof(kf);
  const beslam::registry::Landmarks made = reconstructor.reconstruct(kf, frame, {}, beslam_image_view{});
  ASSERT_EQ(made.size(), 1u);
  EXPECT_EQ(made[0].track_id, 5);
  EXPECT_DOUBLE_EQ(made[0].scale.x(), 4.0);
  EXPECT_FALSE(made[0].removed) << "1.3 fields past a 1.2 plugin's struct read as zero";
  EXPECT_TRUE(made[0].mesh_faces.empty());
  EXPECT_TRUE(reconstructor.finish().empty()) << "no finish() in a 1.2 table: nothing, no call";
}

// ABI 1.4 appends an optional prepare() to the backend's table: a 1.3 backend (56-byte table) still
// loads and the host skips the call; an SDK backend has it.
TEST(Registry, AnAbi13BackendStillLoadsWithoutPrepare) {
  FixtureHost host({"backend_1_3"});
  host.registry.loadLibrary(std::string(PLUGIN_DIR) + "/backend_pose_replay.so");
  auto old_backend = host.create<beslam::registry::BackendInstance>("backend_1_3");
  EXPECT_FALSE(old_backend.hasPrepare());
  beslam_frame frame = emptyFrame();
  EXPECT_NO_THROW(old_backend.prepare(frame));  // no call
  EXPECT_EQ(old_backend.track(frame, beslam_image_view{}, {}).result.state, BESLAM_TRACKING_NOT_INITIALIZED);
  EXPECT_EQ(host.registry.find("backend_pose_replay").functions_size, sizeof(beslam_backend_v1));
}

// ABI 1.5 appends position_sigma and range_drift to the box: a 1.4 detector's 144-byte boxes are read at
// their own stride, and the new fields (and the flag that says they are set) come out zero.
TEST(Registry, AnAbi14DetectorsBoxesReadAsHavingNoPositionSigma) {
  FixtureHost host({"detector_1_4"});
  auto detector = host.create<beslam::registry::DetectorInstance>("detector_1_4");
  beslam_frame frame = emptyFrame();
  const std::vector<beslam_box3d> boxes = detector.detect(frame);
  ASSERT_EQ(boxes.size(), 2u);
  for (size_t i = 0; i < boxes.size(); ++i) {
    EXPECT_DOUBLE_EQ(boxes[i].center_cam[2], 10.0 + static_cast<double>(i));
    EXPECT_FLOAT_EQ(boxes[i].score, 0.5f);
    EXPECT_EQ(boxes[i].flags & BESLAM_BOX_HAS_POSITION_SIGMA, 0u);
    EXPECT_EQ(boxes[i].position_sigma[0], 0.0);
    EXPECT_EQ(boxes[i].position_sigma[1], 0.0);
    EXPECT_EQ(boxes[i].range_drift, 0.0);
  }
}

// ABI 1.7: a backend says how it moved its world, and the host hands that to the motion checker. A 1.6
// checker (16-byte table, no world_moved) still loads and the host skips the call; an SDK checker gets it;
// a change that is not finite is refused by the backend's name.
TEST(Registry, AWorldChangeCrossesFromBackendToMotionChecker) {
  FixtureHost host({"backend_world_moved", "motion_checker_1_6", "sdk_fixtures"});
  auto backend = host.create<beslam::registry::BackendInstance>("backend_world_moved");
  auto old_checker = host.create<beslam::registry::MotionCheckerInstance>("motion_checker_1_6");
  auto checker = host.create<beslam::registry::MotionCheckerInstance>("fixture_all_static",
                                                                      {number("corrupt_nan", BESLAM_CONFIG_BOOL, 0)});
  EXPECT_EQ(host.registry.find("motion_checker_1_6").functions_size, offsetof(beslam_motion_checker_v1, world_moved));
  EXPECT_EQ(host.registry.find("fixture_all_static").functions_size, sizeof(beslam_motion_checker_v1));

  beslam_frame frame = emptyFrame();
  EXPECT_FALSE(backend.track(frame, beslam_image_view{}, {}).worldChange()) << "frame 0: the world stayed";
  frame.index = 1;
  const auto change = backend.track(frame, beslam_image_view{}, {}).worldChange();
  ASSERT_TRUE(change);
  EXPECT_DOUBLE_EQ(change->scale, 1.5);
  const Eigen::Vector3d p_new =
      change->scale * (change->S_new_old.linear() * Eigen::Vector3d(1, 0, 0)) + change->S_new_old.translation();
  EXPECT_TRUE(p_new.isApprox(Eigen::Vector3d(2, 0, -1.5))) << p_new.transpose();
  frame.index = 2;
  EXPECT_FALSE(backend.track(frame, beslam_image_view{}, {}).worldChange());
  frame.index = 3;
  const std::string m = errorOf([&] { backend.track(frame, beslam_image_view{}, {}); });
  EXPECT_NE(m.find("plugin backend_world_moved: track moved the world by a non-finite change"), std::string::npos) << m;

  std::vector<beslam_box3d> boxes(1);
  EXPECT_NO_THROW(old_checker.worldMoved(change->S_new_old, change->scale));  // no call
  old_checker.classify(frame, Eigen::Isometry3d::Identity(), boxes);
  EXPECT_EQ(boxes[0].track_id, 3);
  checker.worldMoved(change->S_new_old, change->scale);
  checker.classify(frame, Eigen::Isometry3d::Identity(), boxes);
  EXPECT_EQ(boxes[0].track_id, 8) << "the SDK checker was told once";
  const std::string bad = errorOf([&] { checker.worldMoved(change->S_new_old, 0.0); });
  EXPECT_NE(bad.find("world change with scale <= 0"), std::string::npos) << bad;
}

// The one checked copy the host and the backends read landmarks through (sdk::fromC): counts that
// promise data the plugin did not give, and mesh faces past the vertices, are refused by name.
TEST(Registry, LandmarkCopiesRefuseCountsWithoutDataAndFacesPastTheVertices) {
  auto errorFor = [](const beslam_landmark_list& list) {
    try {
      beslam::sdk::fromC(&list);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::vector<float> vertices(9, 0.0f);  // three vertices
  std::vector<uint32_t> faces = {0, 1, 3};
  beslam_object_landmark l{};
  l.struct_size = sizeof(l);
  l.track_id = 7;
  l.mesh_vertices = vertices.data();
  l.mesh_vertex_count = 3;
  l.mesh_faces = faces.data();
  l.mesh_face_count = 1;
  const beslam_landmark_list list{&l, 1, sizeof(l)};
  EXPECT_EQ(errorFor(list), "landmark 7 has a mesh face index 3 past its 3 vertices");
  faces[2] = 2;
  ASSERT_EQ(beslam::sdk::fromC(&list).at(0).mesh_faces, faces);
  l.shape_code_size = 4;  // and no shape_code array
  EXPECT_EQ(errorFor(list), "landmark 7 has 4 shape code values without data");
  EXPECT_EQ(errorFor(beslam_landmark_list{nullptr, 2, sizeof(l)}), "2 landmarks without data");
  EXPECT_TRUE(beslam::sdk::fromC(nullptr).empty());
}

TEST(Registry, FindsBuiltInPluginsThroughEnvironment) {
  // ctest sets BESLAM_PLUGIN_PATH to the built-in plugin folder.
  Registry registry;
  registry.addSearchPath(PLUGIN_DIR);
  registry.scan();
  EXPECT_TRUE(registry.problems().empty()) << registry.problems().front();
  EXPECT_NO_THROW(registry.find("backend_pose_replay", BESLAM_KIND_BACKEND));
}

TEST(Registry, LoadForLoadsOnlyTheLibrariesNamedAfterThePlugins) {
  Registry registry;
  registry.addSearchPath(FIXTURE_DIR);  // broken fixtures first: none of them is opened
  registry.addSearchPath(PLUGIN_DIR);
  registry.loadFor({"backend_pose_replay"});
  EXPECT_TRUE(registry.problems().empty()) << registry.problems().front();
  ASSERT_EQ(registry.plugins().size(), 1u);
  EXPECT_NE(registry.find("backend_pose_replay", BESLAM_KIND_BACKEND).library_path.find("backend_pose_replay.so"),
            std::string::npos);
}

TEST(Registry, LoadForOpensOnlyTheFileNamedAfterTheId) {
  Registry registry;
  registry.addSearchPath(FIXTURE_DIR);  // broken fixtures beside it: none of them is opened
  registry.loadFor({"fixture_boxes"});  // fixture_boxes.so: a symlink to sdk_fixtures.so (ALSO_PROVIDES)
  EXPECT_NO_THROW(registry.find("fixture_boxes", BESLAM_KIND_DETECTOR));
  EXPECT_TRUE(registry.problems().empty()) << registry.problems().front();
  ASSERT_EQ(registry.loadedFiles().size(), 1u);
  EXPECT_NE(registry.loadedFiles()[0].find("fixture_boxes.so"), std::string::npos);
}

TEST(Registry, LoadForReportsABrokenLibraryNamedAfterThePluginOnce) {
  Registry registry;
  registry.addSearchPath(FIXTURE_DIR);
  registry.loadFor({"wrong_major"});
  EXPECT_EQ(registry.problems().size(), 1u);
  const std::string message = errorOf([&] { registry.find("wrong_major", BESLAM_KIND_DETECTOR); });
  EXPECT_NE(message.find("wrong_major.so"), std::string::npos) << message;
  EXPECT_NE(message.find("major versions must match"), std::string::npos) << message;
}

namespace {

// A fresh folder of its own under the system's temporary folder, removed (made writable first) at the end.
struct TempFolder {
  std::filesystem::path path;
  explicit TempFolder(const std::string& name)
      : path(std::filesystem::temp_directory_path() /
             ("beslam_registry_test_" + std::to_string(::getpid()) + "_" + name)) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
    std::filesystem::permissions(path, std::filesystem::perms(0755));
  }
  ~TempFolder() {
    std::error_code ec;
    std::filesystem::permissions(path, std::filesystem::perms(0755), ec);
    std::filesystem::remove_all(path, ec);
  }
  // A copy of a real plugin library named `name`.so, with `mode`.
  std::string copy(const std::string& name, std::filesystem::perms mode = std::filesystem::perms(0755)) const {
    const auto to = path / (name + ".so");
    std::filesystem::copy_file(std::string(PLUGIN_DIR) + "/backend_pose_replay.so", to);
    std::filesystem::permissions(to, mode);
    return to.string();
  }
};

}  // namespace

// Probe: an absolute path or ../ traversal as a plugin id must not form a path, let alone load a library.
TEST(Registry, AnIdThatIsNotAPluginIdIsRefusedBeforeAnyPathIsFormed) {
  TempFolder folder("ids");
  folder.copy("trav");
  for (const std::string& id :
       {folder.path.string() + "/trav", std::string("../../../../") + folder.path.string() + "/trav",
        std::string("Backend_Orb"), std::string("backend-orb"), std::string("")}) {
    Registry registry;
    registry.addSearchPath(FIXTURE_DIR);
    const std::string message = errorOf([&] { registry.loadFor({id}); });
    EXPECT_NE(message.find("is not a plugin id (accepted: [a-z0-9_]+"), std::string::npos) << message;
    EXPECT_TRUE(registry.loadedFiles().empty()) << id;
    EXPECT_TRUE(registry.plugins().empty()) << id;
  }
  EXPECT_TRUE(beslam::registry::isPluginId("backend_orb2"));
  EXPECT_FALSE(beslam::registry::isPluginId("a.so"));
}

// Probe: a typo loads nothing at all (it used to load every library of every folder), and the error lists
// the libraries there without opening them.
TEST(Registry, ATypoLoadsNothing) {
  Registry registry;
  registry.addSearchPath(FIXTURE_DIR);
  registry.addSearchPath(PLUGIN_DIR);
  registry.loadFor({"backend_pose_replai"});
  EXPECT_TRUE(registry.loadedFiles().empty());
  EXPECT_TRUE(registry.problems().empty());
  const std::string message = errorOf([&] { registry.find("backend_pose_replai", BESLAM_KIND_BACKEND); });
  EXPECT_NE(message.find("unknown plugin 'backend_pose_replai'"), std::string::npos) << message;
  EXPECT_NE(message.find("no backend_pose_replai.so in the search path"), std::string::npos) << message;
  EXPECT_NE(message.find(" backend_pose_replay"), std::string::npos) << message;  // listed, not loaded
}

// Probe: a search folder anyone (or the group) can write to is refused with one line, also when it holds
// a library named like a built-in that would otherwise be loaded first.
TEST(Registry, AWritableFolderIsRefusedUnlessAllowed) {
  for (const auto mode : {std::filesystem::perms(0777), std::filesystem::perms(0775)}) {
    TempFolder folder("writable");
    folder.copy("backend_pose_replay");
    std::filesystem::permissions(folder.path, mode);
    Registry registry;
    registry.addSearchPath(folder.path.string());
    registry.addSearchPath(PLUGIN_DIR);
    const std::string message = errorOf([&] { registry.loadFor({"backend_pose_replay"}); });
    EXPECT_NE(message.find(folder.path.string() + ": plugin folder is writable by"), std::string::npos) << message;
    EXPECT_NE(message.find("--allow-writable-plugin-dirs"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_TRUE(registry.loadedFiles().empty());

    Registry listing;  // scan() lists the refusal and opens nothing there
    listing.addSearchPath(folder.path.string());
    listing.scan();
    ASSERT_FALSE(listing.problems().empty());
    EXPECT_NE(listing.problems()[0].find(folder.path.string() + ": plugin folder is writable"), std::string::npos)
        << listing.problems()[0];
    for (const std::string& file : listing.loadedFiles())
      EXPECT_EQ(file.find(folder.path.string()), std::string::npos) << file;

    Registry allowed;
    allowed.allowWritable(true);
    allowed.addSearchPath(folder.path.string());
    allowed.loadFor({"backend_pose_replay"});
    ASSERT_EQ(allowed.loadedFiles().size(), 1u);
    EXPECT_EQ(allowed.loadedFiles()[0], (folder.path / "backend_pose_replay.so").string());
  }
}

TEST(Registry, AWritableLibraryIsRefused) {
  TempFolder folder("writable_file");
  const std::string file = folder.copy("backend_pose_replay", std::filesystem::perms(0666));
  const std::string message = refusal(file);
  EXPECT_NE(message.find(file + ": plugin library is writable by others (mode 0666)"), std::string::npos) << message;
  Registry registry;  // before the built-in folder: an error, not a reason to look further
  registry.addSearchPath(folder.path.string());
  const std::string first = errorOf([&] { registry.loadFor({"backend_pose_replay"}); });
  EXPECT_NE(first.find(file + ": plugin library is writable"), std::string::npos) << first;
  EXPECT_TRUE(registry.loadedFiles().empty());
}

// Probe: a text file named like a plugin library is "not a shared library", naming the file.
TEST(Registry, AFakeLibraryIsNotASharedLibrary) {
  TempFolder folder("fake");
  const std::string fake = (folder.path / "fake_plugin.so").string();
  {
    FILE* f = std::fopen(fake.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("#!/bin/sh\necho not a library\n", f);
    std::fclose(f);
  }
  Registry registry;
  registry.addSearchPath(folder.path.string());
  registry.loadFor({"fake_plugin"});
  const std::string message = errorOf([&] { registry.find("fake_plugin", BESLAM_KIND_DETECTOR); });
  EXPECT_NE(message.find("refused " + fake + ": not a shared library (no ELF header"), std::string::npos) << message;
}
