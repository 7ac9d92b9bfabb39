#include "beslam/common/interrupt.hpp"

#include <atomic>
#include <csignal>
#include <cstring>

#include "beslam/common/error.hpp"

namespace beslam {

namespace {

std::atomic<int> g_requested{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free flag");
bool g_installed = false;
struct sigaction g_previous_int, g_previous_term;

extern "C" void onInterrupt(int signal_number) {
  int none = 0;
  if (g_requested.compare_exchange_strong(none, signal_number)) return;
  // Second signal: the user means it. Default action, then deliver it again.
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

}  // namespace

InterruptGuard::InterruptGuard() {
  if (g_installed) throw Error("internal: a second InterruptGuard while one is active");
  g_requested = 0;
  struct sigaction action {};
  action.sa_handler = onInterrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // blocking reads in plugins go on; the loop checks between frames
  if (sigaction(SIGINT, &action, &g_previous_int) != 0 || sigaction(SIGTERM, &action, &g_previous_term) != 0)
    throw Error(std::string("cannot install the SIGINT/SIGTERM handlers: ") + std::strerror(errno));
  g_installed = true;
}

InterruptGuard::~InterruptGuard() {
  sigaction(SIGINT, &g_previous_int, nullptr);
  sigaction(SIGTERM, &g_previous_term, nullptr);
  g_installed = false;
}

int InterruptGuard::requested() { return g_requested.load(); }

std::string signalName(int signal_number) {
  switch (signal_number) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "signal " + std::to_string(signal_number);
  }
}

}  // namespace beslam
