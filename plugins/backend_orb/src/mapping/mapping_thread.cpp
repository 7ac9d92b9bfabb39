#include "mapping/mapping_thread.hpp"

#include "stage_clock.hpp"

namespace beslam::orb {

MappingThread::MappingThread(const ThreadingOptions& options, Process process)
    : threaded_(options.threaded_mapping || options.concurrent_mapping),
      concurrent_(options.concurrent_mapping),
      process_(std::move(process)) {
  if (threaded_) worker_ = std::thread([this] { run(); });
}

MappingThread::~MappingThread() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void MappingThread::run() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (queue_.empty()) return;
      job = queue_.front();
      queue_.pop_front();
      busy_ = true;
    }
    const auto t0 = Clock::now();
    if (concurrent_) {
      gate_.enterMapper();
      stop_ba_ = false;
      process_(job.first, job.second);
      gate_.leaveMapper();  // before busy is cleared: an idle mapper holds no gate
    } else {
      process_(job.first, job.second);
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      background_ms_ += msSince(t0);
      busy_ = false;
    }
    cv_.notify_all();
  }
}

void MappingThread::queue(const std::vector<Job>& jobs) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const Job& j : jobs) queue_.push_back(j);
  }
  cv_.notify_all();
}

void MappingThread::waitIdle() {
  if (!threaded_) return;
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [this] { return queue_.empty() && !busy_; });
}

bool MappingThread::idle() {
  if (!threaded_) return true;
  std::lock_guard<std::mutex> lock(mutex_);
  return queue_.empty() && !busy_;
}

void MappingThread::waitIdleHoldingGate() {
  gate_.leaveTracker();
  waitIdle();
  gate_.enterTracker();
}

double MappingThread::takeBackgroundMs() {
  std::lock_guard<std::mutex> lock(mutex_);
  const double ms = background_ms_;
  background_ms_ = 0;
  return ms;
}

bool MappingThread::acceptKeyFrame() {
  if (idle()) return true;
  stop_ba_ = true;
  return false;
}

}  // namespace beslam::orb
