// Test plugins that go wrong in one way each, chosen by the macro MISBEHAVE when compiled:
// - versions overtake must refuse: old_major (returns 1, as every version-1 plugin does),
//   newer_minor (one minor above the header's), newer_major (the next major version);
// - failures while driving: throws, nan, status, too_many, struct_size (writes over the
//   path's struct_size), quiet (no summary, and fails without a reason: the NULLs the header
//   allows), far (a finite point at 1e300 m), cut_reason (a reason of "é"s formatted into a
//   1,024-byte buffer, so cut after its first byte: not valid UTF-8);
// - failures to start: create_fails (its own formatted reason), create_unterminated (fills
//   the reason buffer without a NUL), create_throws.
// Before they misbehave they answer a straight path, so a run gets going first. One more,
// echo, behaves: it answers the telemetry's fields as points, for the tests of the units and
// of the struct layout; it is also built against the frozen 2.0 header (tests/plugin/abi).

#include <overtake/planner_plugin.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#define OVERTAKE_STR2(x) #x
#define OVERTAKE_STR(x) OVERTAKE_STR2(x)

namespace {
enum class Mode {
  old_major,
  newer_minor,
  newer_major,
  throws,
  nan,
  status,
  too_many,
  struct_size,
  quiet,
  far,
  cut_reason,
  create_fails,
  create_unterminated,
  create_throws,
  echo
};
constexpr Mode kMode = Mode::MISBEHAVE;
constexpr int kGoodCycles = 20;  // cycles planned well before going wrong
const overtake_plugin_info kInfo = {"misbehaving_" OVERTAKE_STR(MISBEHAVE),
                                    kMode == Mode::quiet ? nullptr : "goes wrong on purpose"};
}  // namespace

struct overtake_plugin_handle {
  int cycles = 0;
  size_t setup_size = 0;  // the struct_size of the setup create was given
};

int overtake_plugin_abi_version(void) {
  switch (kMode) {
    case Mode::old_major:
      return 1;
    case Mode::newer_minor:
      return OVERTAKE_PLUGIN_ABI_VERSION + 1;
    case Mode::newer_major:
      return OVERTAKE_PLUGIN_MAKE_VERSION(OVERTAKE_PLUGIN_ABI_MAJOR + 1, 0);
    default:
      return OVERTAKE_PLUGIN_ABI_VERSION;
  }
}

const overtake_plugin_info* overtake_plugin_get_info(void) {
  return &kInfo;
}

overtake_plugin_handle* overtake_plugin_create(const overtake_plugin_setup* setup, char* error,
                                               size_t error_size) {
  switch (kMode) {
    case Mode::create_fails:
      std::snprintf(error, error_size, "no config given for %d lanes", setup->lane_count);
      return nullptr;
    case Mode::create_unterminated:
      std::memset(error, 'x', error_size);
      return nullptr;
    case Mode::create_throws:
      throw std::runtime_error("cannot start");
    default:
      break;
  }
  auto* h = new overtake_plugin_handle;
  h->setup_size = setup->struct_size;
  return h;
}

namespace {

// The telemetry as points: every field, the struct sizes each side knows, whether the empty
// arrays are NULL, the arrays' contents, and (built against 2.1 or later, when the host has
// it) the field 2.1 appended.
int echo(const overtake_plugin_handle& h, const overtake_telemetry& in, overtake_path& out) {
  const double pts[][2] = {
      {in.x, in.y},
      {in.s, in.d},
      {in.yaw, in.speed},
      {static_cast<double>(in.previous_path_count), in.end_path_s},
      {in.end_path_d, static_cast<double>(in.sensor_fusion_count)},
      {static_cast<double>(h.setup_size), static_cast<double>(in.struct_size)},
      {static_cast<double>(out.struct_size), static_cast<double>(sizeof(overtake_telemetry))},
      {in.previous_path_x == nullptr && in.previous_path_y == nullptr ? 1.0 : 0.0,
       in.sensor_fusion == nullptr ? 1.0 : 0.0}};
  std::size_t n = 0;
  for (const auto& p : pts) {
    out.next_x[n] = p[0];
    out.next_y[n++] = p[1];
  }
  for (std::size_t i = 0; i < in.previous_path_count; ++i) {
    out.next_x[n] = in.previous_path_x[i];
    out.next_y[n++] = in.previous_path_y[i];
  }
  for (std::size_t i = 0; i < in.sensor_fusion_count; ++i) {
    for (int k = 0; k < OVERTAKE_SF_COLUMNS; k += 2) {
      out.next_x[n] = in.sensor_fusion[i][k];
      out.next_y[n++] = k + 1 < OVERTAKE_SF_COLUMNS ? in.sensor_fusion[i][k + 1] : 0.0;
    }
  }
#if OVERTAKE_PLUGIN_ABI_MINOR >= 1
  if (OVERTAKE_PLUGIN_HAS_FIELD(&in, overtake_telemetry, speed_mps)) {
    out.next_x[n] = in.speed_mps;
    out.next_y[n++] = 0.0;
  }
#endif
  out.count = n;
  return 0;
}

}  // namespace

int overtake_plugin_plan(overtake_plugin_handle* h, const overtake_telemetry* in,
                         overtake_path* out) {
  if (kMode == Mode::echo) return echo(*h, *in, *out);
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
      case Mode::quiet:
        return 3;  // out->error left NULL
      case Mode::far:
        out->next_x[0] = 1e300;
        out->next_y[0] = 0.0;
        out->count = 1;
        return 0;
      case Mode::cut_reason: {
        static char reason[1024];
        std::string many;
        for (int i = 0; i < 600; ++i) many += "\xC3\xA9";
        std::snprintf(reason, sizeof reason, "%s", many.c_str());
        out->error = reason;
        return 5;
      }
      case Mode::too_many:
        out->count = out->capacity + 1;
        return 0;
      case Mode::struct_size:
        out->struct_size = 0;
        break;  // and a good path: the size alone must fail the cycle
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
