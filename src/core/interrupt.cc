#include "aia/core/interrupt.h"

#include <csignal>

namespace aia {
namespace {

volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void OnInterrupt(int signal) {
  if (g_interrupted) {  // the second Ctrl-C: no more waiting
    std::signal(signal, SIG_DFL);
    std::raise(signal);
    return;
  }
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
