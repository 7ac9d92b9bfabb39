// backend_orb's vocabulary files (`backend.vocabulary`, `beslam vocab`): a bad file is one
// std::runtime_error naming the file; a file that loads gives, for any descriptors, words that are leaves of
// its tree and bag-of-words vectors of finite weights in [0, 1] that sum to 1 (or are empty), scores in [0, 1].
//
// The format ends in a checksum of everything before it, which random bytes never match; so each input is
// tried as it is and with its last 8 bytes made the checksum of the rest.
//
// The seed corpus (corpus/vocabulary/) is written by this binary: BESLAM_FUZZ_WRITE_SEEDS=DIR vocabulary
// trains two small trees (k 3, 2 levels; k 2, 3 levels) on descriptors taken from the shipped vocabulary
// (plugins/backend_orb/data/orb_vocabulary.bvoc) and exits.
#include "place/vocabulary.hpp"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "features/checksum.hpp"
#include "fuzz_support.hpp"

namespace {

namespace place = beslam::orb::place;

void writeSeeds(const std::string& dir) {
  std::ifstream in(BESLAM_SOURCE_DIR "/plugins/backend_orb/data/orb_vocabulary.bvoc", std::ios::binary);
  const std::string shipped((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  constexpr size_t kHeader = 8 + 5 * 4, kNode = 4 + 32 + 4;
  std::vector<cv::Mat> images;
  for (int image = 0; image < 4; ++image) {
    cv::Mat d(16, 32, CV_8U);
    for (int r = 0; r < d.rows; ++r)  // nodes 1.. of the shipped tree: real ORB descriptors' centres
      std::memcpy(d.ptr(r), shipped.data() + kHeader + (1 + 16 * image + r) * kNode + 4, 32);
    images.push_back(d);
  }
  std::filesystem::create_directories(dir);
  place::Vocabulary::train(images, {3, 2, 1, 5}).save(dir + "/k3-l2.bvoc");
  place::Vocabulary::train(images, {2, 3, 1, 5}).save(dir + "/k2-l3.bvoc");
}

// Descriptors the loaded trees transform: fixed bit patterns.
const cv::Mat& probes() {
  static const cv::Mat d = [] {
    cv::Mat m(6, 32, CV_8U);
    for (int r = 0; r < m.rows; ++r)
      for (int c = 0; c < 32; ++c) m.at<uint8_t>(r, c) = static_cast<uint8_t>((r * 37 + c * 11) * (r + 1));
    return m;
  }();
  return d;
}

void check(const std::string& path) {
  place::Vocabulary v;
  try {
    v = place::Vocabulary::load(path);
  } catch (const std::runtime_error& e) {
    beslam::fuzz::require(std::strncmp(e.what(), (path + ": ").c_str(), path.size() + 2) == 0,
                          "a vocabulary error that does not name the file");
    return;
  }
  place::BowVector bow;
  place::FeatureVector fv;
  v.transform(probes(), bow, &fv, 1);
  double sum = 0;
  for (const auto& [word, weight] : bow) {
    beslam::fuzz::require(word < v.numNodes(), "a word that is not a node");
    // >= 0, not > 0: a word whose idf is a denormal next to one of 100 normalises to 0 in float.
    beslam::fuzz::require(std::isfinite(weight) && weight >= 0 && weight <= 1.0001f, "a word weight outside [0, 1]");
    sum += weight;
  }
  beslam::fuzz::require(bow.empty() || std::abs(sum - 1) < 1e-3, "a bag of words that does not sum to 1");
  for (const auto& [node, features] : fv)
    beslam::fuzz::require(node < v.numNodes(), "a direct-index node that is not a node");
  const double s = place::Vocabulary::score(bow, bow);
  beslam::fuzz::require(std::isfinite(s) && s >= 0 && s <= 1.0001, "a score outside [0, 1]");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) { return beslam::fuzz::writeSeedsIfAsked(writeSeeds); }

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  check(beslam::fuzz::writeScratch(data, size, "vocabulary.bvoc"));
  if (size > 8) {
    std::string bytes(reinterpret_cast<const char*>(data), size);
    const uint64_t sum = beslam::orb::fnv1a(bytes.data(), size - 8);
    beslam::fuzz::putLittleEndian64(bytes, size - 8, sum);
    check(beslam::fuzz::writeScratch(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), "fitted.bvoc"));
  }
  return 0;
}
