#pragma once
// The namespaces a contained planner program runs in, step by step, and what the machine
// allows of them (internal to the sandbox target; private_network_available and
// check_planner_network are in planner_process.hpp). The keeper and the probe's child go
// through the same steps; self_map and enter_namespaces are async-signal-safe, as they must
// be there (async_safe.hpp).

#include <cstddef>
#include <string>

namespace overtake::sandbox {

/// Steps of the start that can fail, for the parent's message (kFailed carries one, with
/// errno).
enum Step : int {
  kStepUnshare = 1,
  kStepSetgroups,
  kStepUidMap,
  kStepGidMap,
  kStepLoopback,
  kStepFork,
};

/// "UID UID 1\n" into out[0..size): the user mapped to itself (so that files, `id` and tools
/// see the user, not root; the keeper keeps the capabilities the new namespace gives its
/// maker, and loses them with the program's exec).
void self_map(char* out, std::size_t size, unsigned id);

/// Enters the namespaces (`isolated`: a network one too) and makes them usable. Returns 0, or
/// the step that failed (errno tells why).
[[nodiscard]] int enter_namespaces(bool isolated, bool as_root, const char* uid_map,
                                   const char* gid_map);

/// What failed: "cannot ... (strerror)".
[[nodiscard]] std::string step_text(int step, int err);

/// What failed and how to allow it (or do without).
[[nodiscard]] std::string namespace_advice(int step, int err);

}  // namespace overtake::sandbox
