// KeyFrameDatabase: an inverted index from vocabulary word to the keyframes whose BoW vector has it.
//
// add() indexes a keyframe's BoW vector, erase() removes it, clear() empties the index. Queries pass
// over bad (culled) keyframes. relocalisationCandidates() follows ORB-SLAM2's rule: keyframes sharing
// at least 0.8 x the best share of shared words (counted relative to the keyframe's word count, where
// ORB-SLAM2 uses raw counts), scored by BoW similarity, grouped with their 10 best covisible keyframes;
// the best keyframe of every group scoring above 0.75 x the best group, best group first. Results come
// in a deterministic order (keyframe ids break ties), whatever the pointers' addresses. Each indexed
// keyframe has a slot (a small integer, reused after erase()), and the index lists slots, so counting the
// words a query shares with every keyframe is a pass over flat arrays.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "place/vocabulary.hpp"

namespace beslam::orb {

class KeyFrame;

class KeyFrameDatabase {
 public:
  void add(KeyFrame* kf);
  void erase(KeyFrame* kf);
  void clear();

  // Keyframes that share at least one word with bow, with the number of shared words, in id order.
  std::vector<std::pair<KeyFrame*, int>> sharedWords(const place::BowVector& bow) const;
  // Relocalisation candidates for a frame's BoW vector, best first.
  std::vector<KeyFrame*> relocalisationCandidates(const place::BowVector& bow) const;

 private:
  // Word id -> slots of the keyframes that have it, indexed directly (word ids are the vocabulary's node ids,
  // 47,778 for the default one: 1.1 MB of list headers). A query walks it in word order; a hash map cost
  // a cache miss or two per word more, most of a late query (six laps: 2,700 words, 95,000 postings).
  std::vector<std::vector<int>> index_;
  std::vector<KeyFrame*> slots_;  // slot -> keyframe, nullptr when free
  std::unordered_map<const KeyFrame*, int> slot_of_;
  std::vector<int> free_slots_;
};

}  // namespace beslam::orb
