/* A test plugin in C99 that lacks overtake_plugin_destroy (and shows that the header
 * compiles as C). */
#include <overtake/planner_plugin.h>

#include <stdlib.h>

struct overtake_plugin_handle {
  int unused;
};

static const overtake_plugin_info kInfo = {"missing_symbol", "has no destroy"};

int overtake_plugin_abi_version(void) {
  return OVERTAKE_PLUGIN_ABI_VERSION;
}

const overtake_plugin_info* overtake_plugin_get_info(void) {
  return &kInfo;
}

overtake_plugin_handle* overtake_plugin_create(const overtake_plugin_setup* setup, char* error,
                                               size_t error_size) {
  (void)setup;
  (void)error;
  (void)error_size;
  return calloc(1, sizeof(overtake_plugin_handle));
}

int overtake_plugin_plan(overtake_plugin_handle* handle, const overtake_telemetry* in,
                         overtake_path* out) {
  (void)handle;
  (void)in;
  out->count = 0;
  return 0;
}
