// Helpers for the keeper and init: async-signal-safe only (see async_safe.hpp).

#include "async_safe.hpp"

#include <poll.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <ctime>

namespace overtake::sandbox {

void close_all_but(int from, const int* keep, int n) {
  int sorted[8];
  int m = 0;
  for (int i = 0; i < n && m < 8; ++i) {
    if (keep[i] >= from) sorted[m++] = keep[i];
  }
  std::sort(sorted, sorted + m);
  bool ok = true;
  unsigned next = static_cast<unsigned>(from);
  for (int i = 0; i < m && ok; ++i) {
    const auto k = static_cast<unsigned>(sorted[i]);
    if (k > next) ok = ::syscall(SYS_close_range, next, k - 1, 0U) == 0;
    next = std::max(next, k + 1);
  }
  if (ok && ::syscall(SYS_close_range, next, ~0U, 0U) == 0) return;
  // Kernels before 5.9: one close per possible descriptor.
  rlimit lim{};
  const long top = ::getrlimit(RLIMIT_NOFILE, &lim) == 0 && lim.rlim_cur != RLIM_INFINITY
                       ? std::min<long>(static_cast<long>(lim.rlim_cur), 1L << 20)
                       : 65536L;
  for (long fd = from; fd < top; ++fd) {
    if (std::find(keep, keep + n, static_cast<int>(fd)) == keep + n) ::close(static_cast<int>(fd));
  }
}

double now_ms() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) / 1e6;
}

void sleep_ms(int ms) {
  (void)::poll(nullptr, 0, ms);
}

}  // namespace overtake::sandbox
