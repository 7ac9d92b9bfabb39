#include "place/vocabulary.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "features/checksum.hpp"
#include "matching/hamming.hpp"

namespace beslam::orb::place {
namespace {

constexpr char kMagic[8] = {'B', 'S', 'L', 'M', 'V', 'O', 'C', '\0'};
constexpr size_t kHeaderBytes = 8 + 5 * 4;
constexpr size_t kNodeBytes = 4 + 32 + 4;
constexpr float kMaxWeight = 100;  // ln of the image count: 44 for 2^64 images
constexpr uint32_t kWeightingTfIdf = 1;

// Deterministic on every platform: splitmix64 for seeds, our own uniform draw.
uint64_t splitmix(uint64_t& x) {
  uint64_t z = (x += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
double uniform01(uint64_t& state) { return static_cast<double>(splitmix(state) >> 11) * (1.0 / 9007199254740992.0); }

template <typename T>
void put(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.append(b, sizeof(T));
}
template <typename T>
T get(const std::string& in, size_t& at) {
  T v;
  std::memcpy(&v, in.data() + at, sizeof(T));
  at += sizeof(T);
  return v;
}

// Majority-bit centroid of the descriptors `members` (indices into `all`).
void majority(const std::vector<const uint8_t*>& all, const std::vector<uint32_t>& members, uint8_t out[32]) {
  int counts[256] = {};
  for (uint32_t m : members) {
    const uint8_t* d = all[m];
    for (int byte = 0; byte < 32; ++byte) {
      const uint8_t v = d[byte];
      if (!v) continue;
      for (int bit = 0; bit < 8; ++bit) counts[byte * 8 + bit] += (v >> (7 - bit)) & 1;
    }
  }
  const int half = static_cast<int>(members.size());
  for (int byte = 0; byte < 32; ++byte) {
    uint8_t v = 0;
    for (int bit = 0; bit < 8; ++bit)
      if (2 * counts[byte * 8 + bit] > half) v |= static_cast<uint8_t>(1u << (7 - bit));
    out[byte] = v;
  }
}

}  // namespace

Vocabulary Vocabulary::train(const std::vector<cv::Mat>& images, const VocabularyTrainOptions& options) {
  if (options.k < 2 || options.levels < 1) throw std::invalid_argument("vocabulary: k must be >= 2 and levels >= 1");
  std::vector<const uint8_t*> all;
  for (const cv::Mat& m : images) {
    if (m.empty()) continue;
    if (m.type() != CV_8U || m.cols != 32) throw std::invalid_argument("vocabulary: descriptors must be N x 32 CV_8U");
    for (int r = 0; r < m.rows; ++r) all.push_back(m.ptr<uint8_t>(r));
  }
  if (all.empty()) throw std::invalid_argument("vocabulary: no descriptors to train on");

  Vocabulary v;
  v.k_ = options.k;
  v.levels_ = options.levels;
  v.nodes_.emplace_back();  // root
  // Work list of (node, members); depth-first, children of a node created together.
  struct Task {
    uint32_t node;
    int depth;
    std::vector<uint32_t> members;
  };
  std::vector<Task> stack;
  std::vector<uint32_t> root_members(all.size());
  for (size_t i = 0; i < all.size(); ++i) root_members[i] = static_cast<uint32_t>(i);
  stack.push_back({0, 0, std::move(root_members)});
  const size_t k = static_cast<size_t>(options.k);
  while (!stack.empty()) {
    Task task = std::move(stack.back());
    stack.pop_back();
    const std::vector<uint32_t>& members = task.members;
    // A node at the last level, or with no more descriptors than children, is a word.
    if (task.depth >= options.levels || members.size() <= k) continue;
    uint64_t rng = options.seed * 0x100000001B3ull + task.node;
    splitmix(rng);
    // k-means++ seeding: the next centre drawn with probability ~ squared distance to the nearest one.
    std::vector<std::array<uint8_t, 32>> centres;
    std::vector<double> nearest(members.size(), 1e300);
    size_t pick = static_cast<size_t>(uniform01(rng) * members.size());
    while (centres.size() < k) {
      std::array<uint8_t, 32> c;
      std::memcpy(c.data(), all[members[std::min(pick, members.size() - 1)]], 32);
      centres.push_back(c);
      double total = 0;
      for (size_t i = 0; i < members.size(); ++i) {
        const double d = hamming(all[members[i]], c.data());
        nearest[i] = std::min(nearest[i], d * d);
        total += nearest[i];
      }
      if (total <= 0) break;  // every member sits on a centre already
      double target = uniform01(rng) * total;
      pick = members.size() - 1;
      for (size_t i = 0; i < members.size(); ++i) {
        target -= nearest[i];
        if (target < 0 && nearest[i] > 0) {
          pick = i;
          break;
        }
      }
    }
    if (centres.size() < 2) continue;
    // k-majority rounds: assign to the nearest centre, centres become the clusters' majority bits.
    std::vector<uint32_t> assign(members.size(), 0);
    std::vector<std::vector<uint32_t>> clusters;
    for (int it = 0; it < std::max(1, options.max_iterations); ++it) {
      bool changed = it == 0;
      for (size_t i = 0; i < members.size(); ++i) {
        int best = 257;
        uint32_t best_c = 0;
        for (size_t c = 0; c < centres.size(); ++c) {
          const int d = hamming(all[members[i]], centres[c].data());
          if (d < best) {
            best = d;
            best_c = static_cast<uint32_t>(c);
          }
        }
        if (assign[i] != best_c) changed = true;
        assign[i] = best_c;
      }
      clusters.assign(centres.size(), {});
      for (size_t i = 0; i < members.size(); ++i) clusters[assign[i]].push_back(members[i]);
      if (!changed) break;
      for (size_t c = 0; c < centres.size(); ++c)
        if (!clusters[c].empty()) majority(all, clusters[c], centres[c].data());
    }
    std::vector<size_t> kept;
    for (size_t c = 0; c < centres.size(); ++c)
      if (!clusters[c].empty()) kept.push_back(c);
    if (kept.size() < 2) continue;
    const uint32_t first = static_cast<uint32_t>(v.nodes_.size());
    for (size_t c : kept) {
      Node n;
      n.parent = task.node;
      std::memcpy(n.descriptor, centres[c].data(), 32);
      v.nodes_.push_back(n);
    }
    // Pushed in reverse so the first child is expanded first (depth-first, in id order).
    for (size_t j = kept.size(); j-- > 0;)
      stack.push_back({first + static_cast<uint32_t>(j), task.depth + 1, std::move(clusters[kept[j]])});
  }
  v.buildDerived();
  // idf from the training images: ln(N / images containing the word).
  std::vector<uint32_t> seen_in(v.nodes_.size(), 0);
  std::vector<uint32_t> last_image(v.nodes_.size(), kNoParent);
  uint32_t n_images = 0;
  for (const cv::Mat& m : images) {
    if (m.empty()) continue;
    for (int r = 0; r < m.rows; ++r) {
      const uint32_t w = v.word(m.ptr<uint8_t>(r));
      if (last_image[w] != n_images) {
        last_image[w] = n_images;
        ++seen_in[w];
      }
    }
    ++n_images;
  }
  for (uint32_t w : v.words_)
    v.nodes_[w].weight =
        static_cast<float>(std::log(static_cast<double>(n_images) / std::max<uint32_t>(1, seen_in[w])));
  return v;
}

void Vocabulary::buildDerived() {
  const size_t n = nodes_.size();
  words_.clear();
  child_begin_.assign(n + 1, 0);
  for (uint32_t i = 1; i < n; ++i) {
    ++child_begin_[nodes_[i].parent + 1];
    nodes_[i].depth = nodes_[nodes_[i].parent].depth + 1;
  }
  for (size_t i = 0; i < n; ++i) child_begin_[i + 1] += child_begin_[i];
  children_.assign(n > 0 ? n - 1 : 0, 0);
  std::vector<uint32_t> fill(child_begin_.begin(), child_begin_.end() - 1);
  for (uint32_t i = 1; i < n; ++i) children_[fill[nodes_[i].parent]++] = i;
  for (uint32_t i = 0; i < n; ++i)
    if (child_begin_[i] == child_begin_[i + 1]) words_.push_back(i);
}

void Vocabulary::descend(const uint8_t* d, int direct_depth, uint32_t& leaf, uint32_t& direct) const {
  uint32_t id = 0;
  direct = 0;
  while (child_begin_[id] != child_begin_[id + 1]) {
    int best = 257;
    uint32_t best_id = children_[child_begin_[id]];
    for (uint32_t k = child_begin_[id]; k < child_begin_[id + 1]; ++k) {
      const uint32_t c = children_[k];
      const int dist = hamming(d, nodes_[c].descriptor);
      if (dist < best) {
        best = dist;
        best_id = c;
      }
    }
    id = best_id;
    if (static_cast<int>(nodes_[id].depth) <= direct_depth) direct = id;
  }
  leaf = id;
}

uint32_t Vocabulary::word(const uint8_t* descriptor) const {
  uint32_t leaf = 0, direct = 0;
  descend(descriptor, 0, leaf, direct);
  return leaf;
}

void Vocabulary::transform(const cv::Mat& descriptors, BowVector& bow, FeatureVector* fv, int levels_up) const {
  bow.clear();
  if (fv) fv->clear();
  if (nodes_.empty() || descriptors.empty()) return;
  const int direct_depth = std::max(0, levels_ - levels_up);
  std::vector<std::pair<uint32_t, float>> hits;
  hits.reserve(descriptors.rows);
  for (int r = 0; r < descriptors.rows; ++r) {
    uint32_t leaf = 0, direct = 0;
    descend(descriptors.ptr<uint8_t>(r), direct_depth, leaf, direct);
    if (fv) (*fv)[direct].push_back(r);
    const float w = nodes_[leaf].weight;
    if (w > 0) hits.emplace_back(leaf, w);
  }
  std::sort(hits.begin(), hits.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  double total = 0;
  for (const auto& [word, w] : hits) {
    if (!bow.empty() && bow.back().first == word)
      bow.back().second += w;
    else
      bow.emplace_back(word, w);
    total += w;
  }
  if (total > 0)
    for (auto& e : bow) e.second = static_cast<float>(e.second / total);
}

double Vocabulary::score(const BowVector& a, const BowVector& b) {
  // For L1-normalised vectors 1 - 0.5 |a - b|_1 = 0.5 sum over shared words of (|a| + |b| - |a - b|).
  double s = 0;
  auto i = a.begin(), j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (i->first < j->first) {
      ++i;
    } else if (j->first < i->first) {
      ++j;
    } else {
      s += std::fabs(i->second) + std::fabs(j->second) - std::fabs(i->second - j->second);
      ++i;
      ++j;
    }
  }
  return 0.5 * s;
}

void Vocabulary::save(const std::string& path) const {
  std::string out;
  out.reserve(kHeaderBytes + nodes_.size() * kNodeBytes + 8);
  out.append(kMagic, 8);
  put<uint32_t>(out, kFormatVersion);
  put<uint32_t>(out, static_cast<uint32_t>(k_));
  put<uint32_t>(out, static_cast<uint32_t>(levels_));
  put<uint32_t>(out, kWeightingTfIdf);
  put<uint32_t>(out, static_cast<uint32_t>(nodes_.size()));
  for (const Node& n : nodes_) {
    put<uint32_t>(out, n.parent);
    out.append(reinterpret_cast<const char*>(n.descriptor), 32);
    put<float>(out, n.weight);
  }
  put<uint64_t>(out, fnv1a(out.data(), out.size()));
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw std::runtime_error(path + ": cannot write vocabulary (cannot create " + tmp + ")");
    f.write(out.data(), static_cast<std::streamsize>(out.size()));
    f.close();
    if (!f) {
      std::remove(tmp.c_str());
      throw std::runtime_error(path + ": cannot write vocabulary (write failed)");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error(path + ": cannot write vocabulary (rename failed)");
  }
}

Vocabulary Vocabulary::load(const std::string& path) {
  auto fail = [&](const std::string& problem) -> std::runtime_error {
    return std::runtime_error(path + ": not a usable ORB vocabulary: " + problem);
  };
  std::ifstream f(path, std::ios::binary);
  if (!f) throw fail("cannot open the file");
  f.seekg(0, std::ios::end);
  const std::streamoff size = f.tellg();
  f.seekg(0, std::ios::beg);
  std::string in(size > 0 ? static_cast<size_t>(size) : 0, '\0');
  if (size > 0 && !f.read(in.data(), size)) throw fail("cannot read the file");
  if (std::memcmp(in.data(), kMagic, std::min<size_t>(8, in.size())) != 0 || in.empty())
    throw fail("wrong magic (not a BE-SLAM vocabulary)");
  if (in.size() < kHeaderBytes) throw fail("truncated header (" + std::to_string(in.size()) + " bytes)");
  size_t at = 8;
  const uint32_t version = get<uint32_t>(in, at);
  if (version != kFormatVersion)
    throw fail("format version " + std::to_string(version) + ", this build reads version " +
               std::to_string(kFormatVersion));
  const uint32_t k = get<uint32_t>(in, at), levels = get<uint32_t>(in, at), weighting = get<uint32_t>(in, at);
  const uint32_t count = get<uint32_t>(in, at);
  if (k < 2 || k > 1000 || levels < 1 || levels > 32)
    throw fail("bad tree shape k=" + std::to_string(k) + " L=" + std::to_string(levels));
  if (weighting != kWeightingTfIdf) throw fail("unknown weighting " + std::to_string(weighting));
  const uint64_t expected = kHeaderBytes + static_cast<uint64_t>(count) * kNodeBytes + 8;
  if (count == 0) throw fail("no nodes");
  if (in.size() < expected)
    throw fail("truncated (" + std::to_string(in.size()) + " bytes, expected " + std::to_string(expected) + ")");
  if (in.size() > expected)
    throw fail("trailing data (" + std::to_string(in.size()) + " bytes, expected " + std::to_string(expected) + ")");
  size_t sum_at = expected - 8;
  if (get<uint64_t>(in, sum_at) != fnv1a(in.data(), expected - 8)) throw fail("checksum mismatch (corrupt file)");
  Vocabulary v;
  v.k_ = static_cast<int>(k);
  v.levels_ = static_cast<int>(levels);
  v.nodes_.resize(count);
  for (uint32_t i = 0; i < count; ++i) {
    Node& n = v.nodes_[i];
    n.parent = get<uint32_t>(in, at);
    std::memcpy(n.descriptor, in.data() + at, 32);
    at += 32;
    n.weight = get<float>(in, at);
    if ((i == 0) != (n.parent == kNoParent) || (i > 0 && n.parent >= i))
      throw fail("node " + std::to_string(i) + " has an invalid parent");
    // An idf is ln(images / images with the word): finite, 0 or more, and far below 100. Found by fuzzing: a
    // file with an idf of 7.6e7 loaded; an infinite one would make every bag of words holding that word NaN
    // (inf / inf), and place recognition would then match nothing, silently.
    if (!(n.weight >= 0 && n.weight <= kMaxWeight))
      throw fail("node " + std::to_string(i) + " has weight " + std::to_string(n.weight) + ", not an idf in [0, " +
                 std::to_string(static_cast<int>(kMaxWeight)) + "]");
  }
  v.buildDerived();
  return v;
}

}  // namespace beslam::orb::place
