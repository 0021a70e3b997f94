// Ctrl-C for long jobs: a command that can stop cleanly installs the handler,
// then polls Interrupted() and writes what is done (exit code 130). Commands
// that do not install it keep the default: SIGINT ends the process, and
// their results are committed piece by piece anyway.
#ifndef AIA_CORE_INTERRUPT_H_
#define AIA_CORE_INTERRUPT_H_

namespace aia {

// The exit code of a job stopped by SIGINT or SIGTERM (128 + SIGINT).
inline constexpr int kInterruptedExitCode = 130;

// From now on SIGINT and SIGTERM set a flag instead of ending the process;
// a second one ends it at once, unless it comes within 0.1 s of the first
// (the same request delivered twice, as `timeout -s INT` does).
void InstallInterruptHandler();

// Whether SIGINT or SIGTERM arrived since InstallInterruptHandler().
bool Interrupted();
// Sets that flag as a signal would: a request from within the process (the
// Python package's, at the interpreter's exit, to a running evaluate).
void RequestInterrupt();

// The handler for one job inside a longer-lived process (the Python
// package's evaluate): installed on construction; on destruction the
// previous handlers are back and the flag is cleared.
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

 private:
  struct Saved;
  Saved* saved_;
};

}  // namespace aia

#endif  // AIA_CORE_INTERRUPT_H_
