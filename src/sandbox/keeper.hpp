#pragma once
// The keeper (internal to the sandbox target): the process between overtake and init. Forked
// from overtake, it enters the namespaces, forks init, and serves overtake's requests over
// the wire (wire.hpp) until told to stop or overtake goes. Async-signal-safe only
// (async_safe.hpp): it runs on the plan, made before the fork.

#include <sys/types.h>

namespace overtake::sandbox {

/// What the keeper runs on, all made by overtake before the fork.
struct KeeperPlan {
  int control = -1;  ///< the keeper's end of the socket pair to overtake
  int log = -1;      ///< the program's log, open for writing
  long long log_max_bytes = 0;
  int devnull = -1;
  pid_t parent = 0;  ///< overtake
  bool isolated = false;
  bool namespaces = false;  ///< PID (and user) namespaces; else a subreaper init
  bool as_root = false;
  const char* uid_map = nullptr;
  const char* gid_map = nullptr;
  const char* cwd = nullptr;  ///< may be null
  char* const* argv = nullptr;
};

/// The keeper's life, in the child of overtake's fork; never returns.
[[noreturn]] void keeper_main(KeeperPlan p);

}  // namespace overtake::sandbox
