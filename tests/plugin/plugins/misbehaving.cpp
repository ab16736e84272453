// Test plugins that go wrong in one way each, chosen by the macro MISBEHAVE when compiled:
// wrong_version, throws, nan, status, too_many, create_fails, create_throws. Before they
// misbehave they answer a straight path, so a run gets going first. One more, echo, behaves:
// it answers the telemetry's fields as points, for the tests of the units.

#include <overtake/planner_plugin.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#define OVERTAKE_STR2(x) #x
#define OVERTAKE_STR(x) OVERTAKE_STR2(x)

namespace {
enum class Mode { wrong_version, throws, nan, status, too_many, create_fails, create_throws, echo };
constexpr Mode kMode = Mode::MISBEHAVE;
constexpr int kGoodCycles = 20;  // cycles planned well before going wrong
const overtake_plugin_info_t kInfo = {"misbehaving_" OVERTAKE_STR(MISBEHAVE),
                                      "goes wrong on purpose"};
}  // namespace

struct overtake_plugin_handle {
  int cycles = 0;
};

int overtake_plugin_abi_version(void) {
  return kMode == Mode::wrong_version ? OVERTAKE_PLUGIN_ABI_VERSION + 98
                                      : OVERTAKE_PLUGIN_ABI_VERSION;
}

const overtake_plugin_info_t* overtake_plugin_info(void) {
  return &kInfo;
}

overtake_plugin_handle* overtake_plugin_create(const overtake_plugin_setup* /*setup*/,
                                               const char** error) {
  if (kMode == Mode::create_fails) {
    *error = "no config given";
    return nullptr;
  }
  if (kMode == Mode::create_throws) throw std::runtime_error("cannot start");
  return new overtake_plugin_handle;
}

int overtake_plugin_plan(overtake_plugin_handle* h, const overtake_telemetry* in,
                         overtake_path* out) {
  if (kMode == Mode::echo) {
    const double pts[][2] = {{in->x, in->y},
                             {in->s, in->d},
                             {in->yaw, in->speed},
                             {static_cast<double>(in->previous_path_count), in->end_path_s},
                             {in->end_path_d, static_cast<double>(in->sensor_fusion_count)}};
    std::size_t n = 0;
    for (const auto& p : pts) {
      out->next_x[n] = p[0];
      out->next_y[n++] = p[1];
    }
    for (std::size_t i = 0; i < in->previous_path_count; ++i) {
      out->next_x[n] = in->previous_path_x[i];
      out->next_y[n++] = in->previous_path_y[i];
    }
    for (std::size_t i = 0; i < in->sensor_fusion_count; ++i) {
      for (int k = 0; k < OVERTAKE_SF_COLUMNS; k += 2) {
        out->next_x[n] = in->sensor_fusion[i][k];
        out->next_y[n++] = k + 1 < OVERTAKE_SF_COLUMNS ? in->sensor_fusion[i][k + 1] : 0.0;
      }
    }
    out->count = n;
    return 0;
  }
  if (++h->cycles > kGoodCycles) {
    switch (kMode) {
      case Mode::throws:
        // A C++ exception leaving an extern "C" function (what the header says not to do).
        throw std::runtime_error("planner exploded");
      case Mode::nan:
        out->next_x[0] = std::numeric_limits<double>::quiet_NaN();
        out->next_y[0] = 0.0;
        out->count = 1;
        return 0;
      case Mode::status:
        out->error = "lost track of the lane";
        return 7;
      case Mode::too_many:
        out->count = out->capacity + 1;
        return 0;
      default:
        break;
    }
  }
  // Straight ahead along the heading at about 10 m/s.
  const double yaw = in->yaw * 3.14159265358979323846 / 180.0;
  for (int i = 0; i < 50; ++i) {
    out->next_x[i] = in->x + 0.2 * (i + 1) * std::cos(yaw);
    out->next_y[i] = in->y + 0.2 * (i + 1) * std::sin(yaw);
  }
  out->count = 50;
  return 0;
}

void overtake_plugin_destroy(overtake_plugin_handle* h) {
  delete h;
}
