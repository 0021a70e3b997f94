#include "aia/core/interrupt.h"

#include <time.h>

#include <csignal>

namespace aia {
namespace {

volatile std::sig_atomic_t g_interrupted = 0;
// When the first signal came (CLOCK_MONOTONIC; clock_gettime is
// async-signal-safe).
struct timespec g_first {};

// A second signal within this many nanoseconds of the first is the same
// request delivered twice: coreutils' `timeout -s INT` sends it to the
// process and to its process group, microseconds apart. A person's second
// Ctrl-C comes later.
constexpr long kRepeatNs = 100'000'000;

extern "C" void OnInterrupt(int signal) {
  struct timespec now {};
  clock_gettime(CLOCK_MONOTONIC, &now);
  if (g_interrupted) {
    const long long since =
        static_cast<long long>(now.tv_sec - g_first.tv_sec) * 1'000'000'000 +
        (now.tv_nsec - g_first.tv_nsec);
    if (since < kRepeatNs) return;  // the first one, again
    // The second Ctrl-C: no more waiting.
    std::signal(signal, SIG_DFL);
    std::raise(signal);
    return;
  }
  g_first = now;
  g_interrupted = 1;
}

}  // namespace

void InstallInterruptHandler() {
  struct sigaction action {};
  action.sa_handler = OnInterrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool Interrupted() { return g_interrupted != 0; }

void RequestInterrupt() { g_interrupted = 1; }

struct InterruptScope::Saved {
  struct sigaction int_action {};
  struct sigaction term_action {};
};

InterruptScope::InterruptScope() : saved_(new Saved) {
  sigaction(SIGINT, nullptr, &saved_->int_action);
  sigaction(SIGTERM, nullptr, &saved_->term_action);
  g_interrupted = 0;
  InstallInterruptHandler();
}

InterruptScope::~InterruptScope() {
  sigaction(SIGINT, &saved_->int_action, nullptr);
  sigaction(SIGTERM, &saved_->term_action, nullptr);
  g_interrupted = 0;
  delete saved_;
}

}  // namespace aia
