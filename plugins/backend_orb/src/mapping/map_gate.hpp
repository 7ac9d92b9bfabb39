// MapGate: exclusive access to the map for two threads, the tracker (the caller's thread) and the local
// mapper (its own thread), in the concurrent mapping mode (ThreadingOptions::concurrent_mapping;
// mapping/mapping_thread.hpp).
//
// Contract. Whoever changes or reads the map (keyframes, map points, the keyframe database, the mapper's
// and the tracker's state) holds the gate; feature extraction, which touches no map, runs outside it.
// The mapper holds it for a whole keyframe but calls yieldToTracker() at its safe points (between its
// stages, between the neighbours it triangulates with, between local BA iterations); a waiting tracker
// goes first there, so tracking waits for at most one of those steps, not for a keyframe's mapping. A safe
// point is one where the mapper keeps no map state in local variables that a tracking step could
// invalidate: the tracker in this mode inserts no keyframe, frees nothing, rescales nothing and resets
// nothing while the mapper is busy (OrbSlam waits for it to be idle first).
#pragma once

#include <condition_variable>
#include <mutex>

namespace beslam::orb {

class MapGate {
 public:
  void enterTracker() {
    std::unique_lock<std::mutex> lock(mutex_);
    tracker_waiting_ = true;
    cv_.wait(lock, [this] { return !held_; });
    held_ = true;
    tracker_waiting_ = false;
  }
  void leaveTracker() { leave(); }
  void enterMapper() {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return !held_ && !tracker_waiting_; });
    held_ = true;
  }
  void leaveMapper() { leave(); }
  // Mapper, at a safe point: if the tracker waits, let it through, then take the gate back.
  void yieldToTracker() {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!tracker_waiting_) return;
    held_ = false;
    cv_.notify_all();
    cv_.wait(lock, [this] { return !held_ && !tracker_waiting_; });
    held_ = true;
  }

 private:
  void leave() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      held_ = false;
    }
    cv_.notify_all();
  }
  std::mutex mutex_;
  std::condition_variable cv_;
  bool held_ = false;
  bool tracker_waiting_ = false;
};

}  // namespace beslam::orb
