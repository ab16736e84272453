#pragma once
// Ctrl-C for long commands (bench, view, live runs): while an InterruptScope lives, SIGINT
// and SIGTERM set a flag that the command polls, instead of ending the process, so that it
// can keep what it has done and say so.

#include <atomic>
#include <csignal>

namespace overtake::app {

/// Catches SIGINT and SIGTERM while alive (restoring the previous handlers after); they set
/// flag(). Scopes do not nest.
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;

  /// Set by a signal; cleared when a scope starts. A handler can only reach static storage.
  [[nodiscard]] static std::atomic<bool>& flag();

 private:
  void (*old_int_)(int);
  void (*old_term_)(int);
};

}  // namespace overtake::app
