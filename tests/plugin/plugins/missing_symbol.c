/* A test plugin in C99 that lacks overtake_plugin_destroy (and shows that the header
 * compiles as C). */
#include <overtake/planner_plugin.h>

#include <stdlib.h>

struct overtake_plugin_handle {
  int unused;
};

static const overtake_plugin_info_t kInfo = {"missing_symbol", "has no destroy"};

int overtake_plugin_abi_version(void) {
  return OVERTAKE_PLUGIN_ABI_VERSION;
}

const overtake_plugin_info_t* overtake_plugin_info(void) {
  return &kInfo;
}

overtake_plugin_handle* overtake_plugin_create(const overtake_plugin_setup* setup,
                                               const char** error) {
  (void)setup;
  (void)error;
  return calloc(1, sizeof(overtake_plugin_handle));
}

int overtake_plugin_plan(overtake_plugin_handle* handle, const overtake_telemetry* in,
                         overtake_path* out) {
  (void)handle;
  (void)in;
  out->count = 0;
  return 0;
}
