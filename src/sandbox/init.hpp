#pragma once
// init (internal to the sandbox target): the program's parent, forked by the keeper. PID 1 of
// the new PID namespace, or a child subreaper where there are no namespaces. It starts the
// program, reaps whatever ends, and stops everything when the keeper says so or goes.
// Async-signal-safe only (async_safe.hpp): it runs on what the keeper prepared.

#include <sys/types.h>

namespace overtake::sandbox {

/// What init runs on, all made before the keeper forked it.
struct InitPlan {
  bool pid_namespace = false;
  int lifeline = -1;  ///< read end: a grace (ms) to stop, or EOF when the keeper is gone
  int status = -1;    ///< write end: the program's wait status
  int out = -1;       ///< write end of the program's output pipe
  int devnull = -1;
  const char* cwd = nullptr;
  char* const* argv = nullptr;
};

/// init's life: starts the program and watches over it until the lifeline says stop.
[[noreturn]] void init_main(const InitPlan& p);

}  // namespace overtake::sandbox
