#include "place/keyframe_database.hpp"

#include <algorithm>
#include <map>

#include "map/id_less.hpp"
#include "map/keyframe.hpp"

namespace beslam::orb {

void KeyFrameDatabase::add(KeyFrame* kf) {
  if (slot_of_.count(kf)) return;  // indexed already
  int slot = static_cast<int>(slots_.size());
  if (!free_slots_.empty()) {
    slot = free_slots_.back();
    free_slots_.pop_back();
    slots_[static_cast<size_t>(slot)] = kf;
  } else {
    slots_.push_back(kf);
  }
  slot_of_[kf] = slot;
  for (const auto& [word, weight] : kf->bow) {
    if (word >= index_.size()) index_.resize(static_cast<size_t>(word) + 1);
    index_[word].push_back(slot);
  }
}

void KeyFrameDatabase::erase(KeyFrame* kf) {
  const auto found = slot_of_.find(kf);
  if (found == slot_of_.end()) return;
  const int slot = found->second;
  for (const auto& [word, weight] : kf->bow) {
    if (word >= index_.size()) continue;
    auto& list = index_[word];
    list.erase(std::remove(list.begin(), list.end(), slot), list.end());
  }
  slots_[static_cast<size_t>(slot)] = nullptr;
  free_slots_.push_back(slot);
  slot_of_.erase(found);
}

void KeyFrameDatabase::clear() {
  index_.clear();
  slots_.clear();
  slot_of_.clear();
  free_slots_.clear();
}

std::vector<std::pair<KeyFrame*, int>> KeyFrameDatabase::sharedWords(const place::BowVector& bow) const {
  std::vector<int> count(slots_.size(), 0);
  for (const auto& [word, weight] : bow) {  // words in increasing order: one pass over the index
    if (word >= index_.size()) break;
    for (int slot : index_[word]) ++count[static_cast<size_t>(slot)];
  }
  std::vector<std::pair<KeyFrame*, int>> shared;
  for (size_t slot = 0; slot < slots_.size(); ++slot)
    if (count[slot] > 0 && slots_[slot] && !slots_[slot]->bad) shared.emplace_back(slots_[slot], count[slot]);
  const IdLess<KeyFrame> less;
  std::sort(shared.begin(), shared.end(), [&](const auto& a, const auto& b) { return less(a.first, b.first); });
  return shared;
}

std::vector<KeyFrame*> KeyFrameDatabase::relocalisationCandidates(const place::BowVector& bow) const {
  const auto shared = sharedWords(bow);
  if (shared.empty()) return {};
  // Shared words as a share of the keyframe's words: ORB-SLAM2 compares raw counts, which favours the
  // two initial keyframes (twice the features) so much that with a small vocabulary they were the only
  // candidates left.
  auto share = [](KeyFrame* kf, int n) { return static_cast<double>(n) / std::max<size_t>(1, kf->bow.size()); };
  double max_share = 0;
  for (const auto& [kf, n] : shared) max_share = std::max(max_share, share(kf, n));
  std::map<KeyFrame*, double, IdLess<KeyFrame>> score;
  for (const auto& [kf, n] : shared)
    if (share(kf, n) >= 0.8 * max_share) score[kf] = place::Vocabulary::score(bow, kf->bow);
  if (score.empty()) return {};
  // Each candidate's group: itself and those of its 10 best covisible keyframes that are candidates too.
  struct Group {
    double accumulated;
    KeyFrame* best;
  };
  std::vector<Group> groups;
  double best_accumulated = 0;
  for (const auto& [kf, s] : score) {
    Group g{s, kf};
    double best_single = s;
    for (KeyFrame* n : kf->bestCovisibles(10)) {
      auto it = score.find(n);
      if (it == score.end() || n->bad) continue;
      g.accumulated += it->second;
      if (it->second > best_single) {
        best_single = it->second;
        g.best = n;
      }
    }
    groups.push_back(g);
    best_accumulated = std::max(best_accumulated, g.accumulated);
  }
  std::stable_sort(groups.begin(), groups.end(),
                   [](const Group& a, const Group& b) { return a.accumulated > b.accumulated; });
  std::vector<KeyFrame*> out;
  for (const Group& g : groups) {
    if (g.accumulated <= 0.75 * best_accumulated) break;
    if (std::find(out.begin(), out.end(), g.best) == out.end()) out.push_back(g.best);
  }
  return out;
}

}  // namespace beslam::orb
