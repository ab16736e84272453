#pragma once
// The calling thread's CPU time: what a computation costs, without the time the thread
// waited for a core (on a shared machine the wall clock includes other processes' turns).

#include <ctime>

namespace overtake::core {

/// CPU time consumed by the calling thread so far, in microseconds.
[[nodiscard]] inline double thread_cpu_us() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e6 + static_cast<double>(ts.tv_nsec) * 1e-3;
}

}  // namespace overtake::core
