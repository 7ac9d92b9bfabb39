// Vocabulary: a hierarchical k-majority tree over 256-bit ORB descriptors (bag of binary words).
//
// train(): k-means++ seeding (seeded RNG, Hamming distance) and majority-bit centroids per node, k
// children a node, L levels; the leaves are the words, weighted by idf = ln(N images / images with the
// word). transform(): a descriptor descends to the closest child at each level; the BoW vector is the
// L1-normalised sum of its words' idf weights (sparse, sorted by word), and the direct index groups the
// features by their ancestor `levels_up` levels above the leaves (ORB-SLAM2 uses 4). score(): the L1
// similarity 1 - 0.5 |v1 - v2|_1 in [0, 1]. Same descriptors, options and seed: byte-identical file.
//
// File (little-endian): magic "BSLMVOC\0", u32 format version, u32 k, u32 L, u32 weighting (1 = tf-idf),
// u32 node count, then per node u32 parent (root: 0xFFFFFFFF), 32-byte descriptor, f32 weight; then
// u64 FNV-1a checksum of everything before it. load() refuses a wrong magic, version, size or checksum
// with one std::runtime_error naming the file and the problem; save() writes a temporary file and
// renames it over the target.
#pragma once

#include <cstdint>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

namespace beslam::orb::place {

// Sparse word -> weight, sorted by word id, L1-normalised.
using BowVector = std::vector<std::pair<uint32_t, float>>;
// Node id -> indices of the features below it (the direct index).
using FeatureVector = std::map<uint32_t, std::vector<int>>;

struct VocabularyTrainOptions {
  int k = 10;               // children per node
  int levels = 6;           // depth of the tree (words are at most this deep)
  uint64_t seed = 1;        // k-means++ seeding
  int max_iterations = 10;  // k-majority rounds per node
};

class Vocabulary {
 public:
  static constexpr uint32_t kFormatVersion = 1;
  static constexpr uint32_t kNoParent = 0xFFFFFFFFu;

  Vocabulary() = default;

  // images: one N x 32 CV_8U descriptor matrix per training image.
  static Vocabulary train(const std::vector<cv::Mat>& images, const VocabularyTrainOptions& options);
  static Vocabulary load(const std::string& path);  // throws std::runtime_error
  void save(const std::string& path) const;         // throws std::runtime_error

  bool empty() const { return nodes_.empty(); }
  int k() const { return k_; }
  int levels() const { return levels_; }
  size_t numNodes() const { return nodes_.size(); }
  size_t numWords() const { return words_.size(); }

  // The word (leaf node id) of one 32-byte descriptor.
  uint32_t word(const uint8_t* descriptor) const;
  // BoW vector of descriptors (N x 32); when fv is given, the direct index at levels_up above the leaves.
  void transform(const cv::Mat& descriptors, BowVector& bow, FeatureVector* fv = nullptr, int levels_up = 4) const;
  static double score(const BowVector& a, const BowVector& b);

 private:
  struct Node {
    uint32_t parent = kNoParent;
    uint8_t descriptor[32] = {};
    float weight = 0;  // idf for words, 0 elsewhere
    uint32_t depth = 0;
  };
  void descend(const uint8_t* d, int direct_depth, uint32_t& leaf, uint32_t& direct) const;
  void buildDerived();  // children, depth and word list from the parent links

  int k_ = 0, levels_ = 0;
  std::vector<Node> nodes_;
  std::vector<uint32_t> child_begin_;  // children of node i: children_[child_begin_[i] .. child_begin_[i + 1])
  std::vector<uint32_t> children_;
  std::vector<uint32_t> words_;  // node ids of the leaves
};

}  // namespace beslam::orb::place
