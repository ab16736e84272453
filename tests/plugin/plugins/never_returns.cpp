// A test plugin whose plan() never returns: it sleeps in a loop forever, the way a planner
// stuck in a search without a deadline would. Nothing from outside can stop it (a C++ plugin
// cannot be interrupted), so it is what the tests of overtake's reply watchdog use to check
// that a stuck in-process planner ends the run with a message instead of hanging it.

#include <overtake/planner_plugin.h>

#include <unistd.h>

namespace {
const overtake_plugin_info kInfo = {"never_returns", "plans forever: plan() never returns"};
}

struct overtake_plugin_handle {
  int unused = 0;
};

int overtake_plugin_abi_version(void) {
  return OVERTAKE_PLUGIN_ABI_VERSION;
}

const overtake_plugin_info* overtake_plugin_get_info(void) {
  return &kInfo;
}

overtake_plugin_handle* overtake_plugin_create(const overtake_plugin_setup* /*setup*/,
                                               char* /*error*/, size_t /*error_size*/) {
  return new overtake_plugin_handle;
}

int overtake_plugin_plan(overtake_plugin_handle* /*handle*/, const overtake_telemetry* /*in*/,
                         overtake_path* /*out*/) {
  for (;;) ::sleep(1);  // a call with a side effect each time round: not a loop to optimise
}

void overtake_plugin_destroy(overtake_plugin_handle* handle) {
  delete handle;
}
