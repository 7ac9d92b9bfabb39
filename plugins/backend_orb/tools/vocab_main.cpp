// beslam-vocab (also `beslam vocab ...`): ORB vocabularies for backend_orb's place recognition.
//   beslam-vocab train --images DIR [--images DIR]... --out FILE [--k 10] [--levels 6] [--seed 1]
//                      [--max-images N] [--features 1000]
//   beslam-vocab info FILE
//   beslam-vocab rank --vocabulary FILE --images DIR [--features 1000] [--max-images N] [--gap 1]
// train: features from the project's own ORB extractor on every image (sorted by path, evenly thinned to
// --max-images), then the seeded k-majority tree; same inputs and seed give a byte-identical file.
// rank: how well the vocabulary tells neighbouring frames of a sequence: odd frames query the even
// ones at least --gap frames away; prints recall@1 (the best match is one of the nearest allowed frames,
// at most gap + 1 away) and the mean score ratio of the nearest allowed frame to frames more than 20 away. Errors: one
// line "beslam-vocab: error: ...", exit 1 (2 for usage).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "beslam/sdk/cli_args.hpp"
#include "features/orb_extractor.hpp"
#include "place/vocabulary.hpp"

namespace fs = std::filesystem;
using beslam::orb::place::BowVector;
using beslam::orb::place::Vocabulary;

namespace {

constexpr const char* kUsage =
    "usage: beslam vocab <command> [options]\n"
    "\n"
    "  train --images DIR [--images DIR]... --out FILE [--k 10] [--levels 6] [--seed 1]\n"
    "        [--max-images N] [--features 1000]\n"
    "        train a vocabulary on every image under the folders (png, jpg, pgm, ppm, bmp)\n"
    "  info FILE\n"
    "        print a vocabulary's shape\n"
    "  rank --vocabulary FILE --images DIR [--features 1000] [--max-images N] [--gap 1]\n"
    "        score how well it ranks a sequence's neighbouring frames first\n";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::vector<std::string> imagesUnder(const std::vector<std::string>& dirs, int max_images) {
  std::vector<std::string> files;
  for (const std::string& dir : dirs) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw std::runtime_error(dir + ": not a folder");
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
      if (!e.is_regular_file()) continue;
      std::string ext = e.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
      if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".ppm" || ext == ".bmp")
        files.push_back(e.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::runtime_error("no images under the given folders");
  if (max_images > 0 && static_cast<int>(files.size()) > max_images) {
    std::vector<std::string> thinned;
    for (int i = 0; i < max_images; ++i) thinned.push_back(files[i * files.size() / max_images]);
    files.swap(thinned);
  }
  return files;
}

cv::Mat describe(const beslam::orb::OrbExtractor& extractor, const std::string& file) {
  const cv::Mat grey = cv::imread(file, cv::IMREAD_GRAYSCALE);
  if (grey.empty()) throw std::runtime_error(file + ": cannot read the image");
  return extractor.extract(grey, cv::Mat())->descriptors.clone();
}

int intArg(const std::string& key, const std::string& value) {
  try {
    size_t used = 0;
    const long v = std::stol(value, &used);
    if (used != value.size() || v < 0 || v > 100000000) throw std::invalid_argument(value);
    return static_cast<int>(v);
  } catch (const std::exception&) {
    throw UsageError(key + ": expected a non-negative integer, got '" + value + "'");
  }
}

int train(const std::vector<std::string>& args) {
  std::vector<std::string> dirs;
  std::string out;
  beslam::orb::place::VocabularyTrainOptions options;
  int max_images = 0, features = 1000;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (i + 1 >= args.size()) throw UsageError(a + " needs a value");
    const std::string& v = args[++i];
    if (a == "--images") {
      dirs.push_back(v);
    } else if (a == "--out") {
      out = v;
    } else if (a == "--k") {
      options.k = intArg(a, v);
    } else if (a == "--levels") {
      options.levels = intArg(a, v);
    } else if (a == "--seed") {
      options.seed = static_cast<uint64_t>(intArg(a, v));
    } else if (a == "--max-images") {
      max_images = intArg(a, v);
    } else if (a == "--features") {
      features = intArg(a, v);
    } else {
      throw UsageError("unknown option " + a);
    }
  }
  if (dirs.empty() || out.empty()) throw UsageError("train needs --images DIR and --out FILE");
  if (options.k < 2 || options.levels < 1 || options.levels > 10)
    throw UsageError("--k must be >= 2, --levels in 1..10");
  if (features < 100) throw UsageError("--features must be >= 100");
  const auto t0 = std::chrono::steady_clock::now();
  const auto files = imagesUnder(dirs, max_images);
  beslam::orb::ExtractorOptions eo;
  eo.features = features;
  const beslam::orb::OrbExtractor extractor(eo);
  std::vector<cv::Mat> descriptors;
  size_t total = 0;
  for (const std::string& f : files) {
    descriptors.push_back(describe(extractor, f));
    total += descriptors.back().rows;
  }
  const Vocabulary vocabulary = Vocabulary::train(descriptors, options);
  vocabulary.save(out);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%s: k %d, L %d, %zu nodes, %zu words from %zu descriptors of %zu images (seed %llu, %.1f s)\n",
              out.c_str(), vocabulary.k(), vocabulary.levels(), vocabulary.numNodes(), vocabulary.numWords(), total,
              files.size(), static_cast<unsigned long long>(options.seed), s);
  return 0;
}

int info(const std::vector<std::string>& args) {
  if (args.size() != 1) throw UsageError("info needs one FILE");
  const Vocabulary v = Vocabulary::load(args[0]);
  std::printf("%s: k %d, L %d, %zu nodes, %zu words, format version %u\n", args[0].c_str(), v.k(), v.levels(),
              v.numNodes(), v.numWords(), Vocabulary::kFormatVersion);
  return 0;
}

int rank(const std::vector<std::string>& args) {
  std::string file, dir;
  int features = 1000, max_images = 0, gap = 1;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (i + 1 >= args.size()) throw UsageError(a + " needs a value");
    const std::string& v = args[++i];
    if (a == "--vocabulary") {
      file = v;
    } else if (a == "--images") {
      dir = v;
    } else if (a == "--features") {
      features = intArg(a, v);
    } else if (a == "--max-images") {
      max_images = intArg(a, v);
    } else if (a == "--gap") {
      gap = std::max(1, intArg(a, v));
    } else {
      throw UsageError("unknown option " + a);
    }
  }
  if (file.empty() || dir.empty()) throw UsageError("rank needs --vocabulary FILE and --images DIR");
  const Vocabulary vocabulary = Vocabulary::load(file);
  const auto files = imagesUnder({dir}, max_images);
  beslam::orb::ExtractorOptions eo;
  eo.features = features;
  const beslam::orb::OrbExtractor extractor(eo);
  std::vector<BowVector> bows(files.size());
  for (size_t i = 0; i < files.size(); ++i) vocabulary.transform(describe(extractor, files[i]), bows[i]);
  int queries = 0, hits = 0;
  double ratio_sum = 0;
  for (size_t q = 1; q < files.size(); q += 2) {
    double best = -1, adjacent = 0, far_sum = 0;
    size_t best_j = 0;
    int far_n = 0;
    for (size_t j = 0; j < files.size(); j += 2) {
      const size_t gap_j = q > j ? q - j : j - q;
      if (static_cast<int>(gap_j) < gap) continue;
      const double s = Vocabulary::score(bows[q], bows[j]);
      if (s > best) {
        best = s;
        best_j = j;
      }
      if (static_cast<int>(gap_j) <= gap + 1) adjacent = std::max(adjacent, s);
      if (gap_j > 20) {
        far_sum += s;
        ++far_n;
      }
    }
    ++queries;
    hits += static_cast<int>(q > best_j ? q - best_j : best_j - q) <= gap + 1;
    if (far_n > 0 && far_sum > 0) ratio_sum += adjacent / (far_sum / far_n);
  }
  std::printf("%s on %s: %d queries, gap %d: recall@1 %.3f, nearest/far score ratio %.2f\n", file.c_str(), dir.c_str(),
              queries, gap, queries ? static_cast<double>(hits) / queries : 0.0, queries ? ratio_sum / queries : 0.0);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> all(argv + 1, argv + argc);
  const auto dispatch = [&]() -> int {
    if (all.empty() || all[0] == "--help" || all[0] == "-h") {
      std::cout << kUsage;
      return all.empty() ? 2 : 0;
    }
    const std::vector<std::string> rest(all.begin() + 1, all.end());
    if (all[0] == "train") return train(rest);
    if (all[0] == "info") return info(rest);
    if (all[0] == "rank") return rank(rest);
    throw UsageError("unknown command '" + all[0] + "'");
  };
  return beslam::cli::runMain<UsageError>(dispatch, std::cerr, kUsage,
                                          "beslam-vocab: error: ", "beslam-vocab: error: ");
}
