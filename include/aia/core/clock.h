// Wall-clock timing of phases and jobs: seconds since a point of the
// monotonic clock (one definition for the episode's phases, the commands'
// totals and the trainer's rates).
#ifndef AIA_CORE_CLOCK_H_
#define AIA_CORE_CLOCK_H_

#include <chrono>

namespace aia {

using SteadyClock = std::chrono::steady_clock;

inline double SecondsSince(SteadyClock::time_point t0) {
  return std::chrono::duration<double>(SteadyClock::now() - t0).count();
}

}  // namespace aia

#endif  // AIA_CORE_CLOCK_H_
