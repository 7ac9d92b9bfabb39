// MappingThread: where each new keyframe's local mapping (and loop closing) runs, by
// Options::threading: inline in the caller's track() (default), on a worker thread that the next frame's
// tracking waits for (threaded_mapping: the same results), or on a worker while tracking goes on
// (concurrent_mapping, ORB-SLAM2's model: the map is shared through gate(), mapping/map_gate.hpp; results
// depend on thread timing). It owns the worker, its queue and the gate; what a keyframe's mapping does is
// the `process` callback (the facade's: LocalMapper, then LoopCloser). Moves no pose itself (poses T_cw are
// the map's).
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "beslam_orb/options.hpp"
#include "map/map_fwd.hpp"
#include "mapping/map_gate.hpp"

namespace beslam::orb {

class MappingThread {
 public:
  // A keyframe to map; initial: one of the two keyframes of the initial map (no BA, no loop search).
  using Job = std::pair<KeyFrame*, bool>;
  using Process = std::function<void(KeyFrame*, bool initial)>;

  // Starts the worker when `options` ask for one (concurrent_mapping implies threaded_mapping).
  MappingThread(const ThreadingOptions& options, Process process);
  ~MappingThread();  // stops the worker once its queue is empty
  MappingThread(const MappingThread&) = delete;
  MappingThread& operator=(const MappingThread&) = delete;

  bool threaded() const { return threaded_; }
  bool concurrent() const { return concurrent_; }

  // Threaded: queues the jobs for the worker (returns at once). Inline: not to be called (the caller maps).
  void queue(const std::vector<Job>& jobs);
  // Threaded: waits until the queue is empty and the worker idle. Inline: returns at once.
  void waitIdle();
  bool idle();
  // Concurrent, the tracker holding the gate: waits for an idle mapper (which needs the gate to finish),
  // then takes the gate back.
  void waitIdleHoldingGate();
  // The worker's mapping time (ms) since the last call.
  double takeBackgroundMs();

  // Concurrent: the map's gate, and the flag that asks the mapper to cut its local BA short.
  MapGate& gate() { return gate_; }
  const std::atomic<bool>& stopBa() const { return stop_ba_; }
  // Concurrent: whether mapping can take a keyframe now; if not, its local BA is asked to stop early
  // (ORB-SLAM2: the mapper cuts its local BA short to take the next keyframe sooner).
  bool acceptKeyFrame();

 private:
  void run();

  const bool threaded_, concurrent_;
  Process process_;
  MapGate gate_;
  std::atomic<bool> stop_ba_{false};
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Job> queue_;  // keyframes waiting for local mapping
  bool busy_ = false, stop_ = false;
  double background_ms_ = 0;
  std::thread worker_;  // last: started once the rest is made
};

}  // namespace beslam::orb
