// Helpers for the dataset tests: a self-deleting temp folder, small file writers, error-message checks.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "beslam/common/error.hpp"
#include "beslam/datasets/dataset.hpp"
#include "beslam/datasets/velodyne.hpp"

namespace beslam::datasets::test {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() / ("beslam_datasets_" + std::string(info ? info->name() : "x") + "_" +
                                         std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string str() const { return path_.string(); }
  std::string operator/(const std::string& rel) const { return (path_ / rel).string(); }

 private:
  fs::path path_;
};

inline void writeText(const std::string& path, const std::string& text) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
  ASSERT_TRUE(out.good()) << path;
}

inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A deterministic test pattern: value depends on x, y and seed; colour images get distinct channels.
inline cv::Mat pattern(int width, int height, int channels, int seed = 0) {
  cv::Mat image(height, width, CV_8UC(channels));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < channels; ++c)
        image.ptr<unsigned char>(y)[x * channels + c] =
            static_cast<unsigned char>((x * 7 + y * 13 + c * 50 + seed) & 0xFF);
  return image;
}

inline void writePng(const std::string& path, int width, int height, int channels = 1, int seed = 0) {
  fs::create_directories(fs::path(path).parent_path());
  ASSERT_TRUE(cv::imwrite(path, pattern(width, height, channels, seed))) << path;
}

inline void writeScan(const std::string& path, int points) {
  fs::create_directories(fs::path(path).parent_path());
  std::vector<float> xyzr(4 * static_cast<std::size_t>(points));
  for (std::size_t i = 0; i < xyzr.size(); i += 4) {
    xyzr[i] = float(i);
    xyzr[i + 1] = -float(i);
    xyzr[i + 2] = 0.5f;
    xyzr[i + 3] = 0.25f;
  }
  writeVelodyneBin(path, xyzr);
}

inline void truncateFile(const std::string& path, std::size_t keep) {
  const std::string bytes = readBytes(path);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes.substr(0, keep);
}

// The shared real data folder, or "" (the caller GTEST_SKIPs).
inline std::string sharedData(const std::string& rel) {
  const fs::path path = fs::path(BESLAM_SHARED_DATA) / rel;
  return fs::exists(path) ? path.string() : std::string();
}

// The options that open `sequence` of the layout `type` under root.
inline DatasetOptions datasetOptions(const std::string& type, const std::string& root, const std::string& sequence) {
  DatasetOptions o;
  o.type = type;
  o.root = root;
  o.sequence = sequence;
  return o;
}

}  // namespace beslam::datasets::test

// Expects `statement` to throw beslam::Error whose message contains every one of the given substrings.
#define EXPECT_BESLAM_ERROR(statement, ...)                                           \
  do {                                                                                \
    try {                                                                             \
      statement;                                                                      \
      ADD_FAILURE() << "expected beslam::Error from: " #statement;                    \
    } catch (const beslam::Error& e) {                                                \
      for (const std::string& part : std::initializer_list<std::string>{__VA_ARGS__}) \
        EXPECT_NE(std::string(e.what()).find(part), std::string::npos)                \
            << "message '" << e.what() << "' lacks '" << part << "'";                 \
    }                                                                                 \
  } while (0)
