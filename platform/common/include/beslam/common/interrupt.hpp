// Stopping a long job cleanly on SIGINT / SIGTERM.
// While an InterruptGuard lives, the first SIGINT or SIGTERM is only recorded: requested() returns its
// number and the job (e.g. the frame loop) stops at its next safe point and writes what it has. A second
// signal of either kind restores the default action and re-raises it, so the process ends at once.
// One guard at a time per process; the handler touches nothing but a lock-free atomic.
#pragma once

#include <string>

namespace beslam {

class InterruptGuard {
 public:
  InterruptGuard();   // installs the handlers (throws beslam::Error if one cannot be installed)
  ~InterruptGuard();  // restores the previous handlers
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

  // The first signal received since construction (SIGINT or SIGTERM), 0 for none.
  static int requested();
};

// "SIGINT", "SIGTERM", ... ("signal N" for others).
std::string signalName(int signal_number);

}  // namespace beslam
