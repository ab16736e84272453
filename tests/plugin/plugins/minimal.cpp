// The least a plugin can do, for measuring the cost of the plugin boundary (bench/): keep
// the previous path and extend it straight along its last heading at the ego's speed. The
// same work as an in-process policy is in bench/plugin_bench.cpp.

#include <overtake/planner_plugin.h>

#include <cmath>

namespace {
const overtake_plugin_info kInfo = {"minimal", "extends the previous path straight ahead"};
}

struct overtake_plugin_handle {
  double dt = 0.02;
};

int overtake_plugin_abi_version(void) {
  return OVERTAKE_PLUGIN_ABI_VERSION;
}
const overtake_plugin_info* overtake_plugin_get_info(void) {
  return &kInfo;
}

overtake_plugin_handle* overtake_plugin_create(const overtake_plugin_setup* setup, char* /*error*/,
                                               size_t /*error_size*/) {
  auto* h = new overtake_plugin_handle;
  h->dt = setup->step_time;
  return h;
}

int overtake_plugin_plan(overtake_plugin_handle* h, const overtake_telemetry* in,
                         overtake_path* out) {
  const double kPi = 3.14159265358979323846;
  double x = in->x, y = in->y, yaw = in->yaw * kPi / 180.0;
  const double step = std::fmax(in->speed / 2.23693629, 1.0) * h->dt;
  std::size_t n = 0;
  for (; n < in->previous_path_count && n < out->capacity; ++n) {
    out->next_x[n] = in->previous_path_x[n];
    out->next_y[n] = in->previous_path_y[n];
  }
  if (n >= 2) {
    x = out->next_x[n - 1];
    y = out->next_y[n - 1];
    yaw = std::atan2(y - out->next_y[n - 2], x - out->next_x[n - 2]);
  }
  for (; n < 50 && n < out->capacity; ++n) {
    x += step * std::cos(yaw);
    y += step * std::sin(yaw);
    out->next_x[n] = x;
    out->next_y[n] = y;
  }
  out->count = n;
  return 0;
}

void overtake_plugin_destroy(overtake_plugin_handle* h) {
  delete h;
}
