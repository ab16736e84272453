#pragma once
// Helpers for the keeper and init (internal to the sandbox target): processes forked from one
// that may run many threads (a bench), which never exec overtake's code again and so may use
// only async-signal-safe calls: system calls on buffers prepared before the fork; no
// allocation, no stdio, no locks. Everything here keeps to that.

namespace overtake::sandbox {

/// Closes every descriptor from `from` up, except those in keep[0..n) (n <= 8).
void close_all_but(int from, const int* keep, int n);

/// The monotonic clock, in milliseconds.
[[nodiscard]] double now_ms();

/// Sleeps `ms` milliseconds (poll without descriptors).
void sleep_ms(int ms);

}  // namespace overtake::sandbox
