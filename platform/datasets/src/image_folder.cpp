// A plain folder of images (type images): <root>/*.{png,jpg,jpeg,pgm,ppm,bmp,tif,tiff,webp} in name order
// (digit runs compared as numbers: img2 before img10), timestamps from <root>/times.txt (one per image) or
// the camera file's fps; the camera from the camera file (options.calibration, required).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "beslam/common/error.hpp"
#include "beslam/datasets/image_io.hpp"
#include "dataset_impl.hpp"

namespace beslam::datasets::detail {
namespace {

namespace fs = std::filesystem;

bool isImageName(const std::string& name) {
  std::string ext = fs::path(name).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  for (const char* e : {".png", ".jpg", ".jpeg", ".pgm", ".ppm", ".bmp", ".tif", ".tiff", ".webp"})
    if (ext == e) return true;
  return false;
}

// Name order with digit runs compared by value ("frame9.png" < "frame10.png"), then plain byte order.
bool naturalLess(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i])), db = std::isdigit(static_cast<unsigned char>(b[j]));
    if (da && db) {
      std::size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      std::size_t ia = i, jb = j;  // skip leading zeros, then compare by length and digits
      while (ia + 1 < ie && a[ia] == '0') ++ia;
      while (jb + 1 < je && b[jb] == '0') ++jb;
      if (ie - ia != je - jb) return ie - ia < je - jb;
      const int cmp = a.compare(ia, ie - ia, b, jb, je - jb);
      if (cmp != 0) return cmp < 0;
      i = ie, j = je;
    } else {
      if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
      ++i, ++j;
    }
  }
  if (a.size() - i != b.size() - j) return a.size() - i < b.size() - j;
  return a < b;
}

}  // namespace

std::unique_ptr<Dataset> openImageFolder(const DatasetOptions& options) {
  requireDirectory(options.root, "image");
  const CameraCalibration calibration = requiredCameraFile(options, "images");

  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(options.root, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (isImageName(name) && isFile(it->path().string())) names.push_back(name);
  }
  if (ec) throwAt(options.root, "cannot list folder: " + ec.message());
  if (names.empty())
    throwAt(options.root, "no images in the folder (accepted: .png .jpg .jpeg .pgm .ppm .bmp .tif .tiff .webp)");
  std::sort(names.begin(), names.end(), naturalLess);

  const std::string times_path = joinPath(options.root, "times.txt");
  std::vector<double> times;
  std::string time_text;
  if (isFile(times_path)) {
    times = readTimes(times_path);
    if (times.size() != names.size())
      throwAt(times_path, "has " + std::to_string(times.size()) + " timestamps but the folder has " +
                              std::to_string(names.size()) + " images (one time in seconds per image, in name order)");
    for (std::size_t k = 1; k < times.size(); ++k)
      if (!(times[k] > times[k - 1]))
        throwAt(times_path, "timestamps must increase (row " + std::to_string(k + 1) + ": " + std::to_string(times[k]) +
                                " after " + std::to_string(times[k - 1]) + ")");
    time_text = ", times.txt";
  } else if (calibration.fps) {
    for (std::size_t k = 0; k < names.size(); ++k) times.push_back(static_cast<double>(k) / *calibration.fps);
    std::ostringstream text;
    text << ", " << *calibration.fps << " fps";
    time_text = text.str();
  } else {
    throwAt(times_path, "missing, and the camera file " + calibration.source +
                            " has no fps: give one of them for the frame timestamps");
  }

  std::vector<std::int64_t> indices(names.size());
  for (std::size_t k = 0; k < names.size(); ++k) indices[k] = static_cast<std::int64_t>(k);
  DatasetContents c;
  for (std::size_t p : selectFrames(indices, options, options.root)) {
    FrameEntry f;
    f.index = static_cast<std::int64_t>(p);
    f.timestamp = times[p];
    f.image_path = joinPath(options.root, names[p]);
    c.frames.push_back(std::move(f));
  }
  const std::string camera_text =
      useCalibration(c, calibration, readImageSize(c.frames.front().image_path), c.frames.front().image_path);
  if (!options.ego_poses.empty()) c.ground_truth = selectPoses(options.ego_poses, names.size(), c.frames);
  c.load_color = options.load_color;
  c.load_lidar = false;
  std::filesystem::path normal = std::filesystem::absolute(options.root).lexically_normal();
  if (normal.filename().empty()) normal = normal.parent_path();
  c.description = "image folder " + normal.filename().string() + " (" + std::to_string(c.frames.size()) + " frames" +
                  time_text + camera_text + rangeText(options, c.frames, names.size()) +
                  (options.ego_poses.empty() ? "" : ", poses " + options.ego_poses) + ")";
  return std::make_unique<LoadedDataset>(std::move(c));
}

}  // namespace beslam::datasets::detail
