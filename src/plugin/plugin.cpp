#include "overtake/plugin/plugin.hpp"

#include <dlfcn.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <memory>
#include <string_view>
#include <utility>
#include <vector>

#include "overtake/core/text_check.hpp"
#include "overtake/core/units.hpp"
#include "overtake/core/wire_number.hpp"
#include "overtake/planner/params.hpp"
#include "overtake/planner_plugin.h"

namespace overtake::plugin {
namespace {

using AbiVersionFn = int (*)();
using InfoFn = const overtake_plugin_info* (*)();
using CreateFn = overtake_plugin_handle* (*)(const overtake_plugin_setup*, char*, std::size_t);
using PlanFn = int (*)(overtake_plugin_handle*, const overtake_telemetry*, overtake_path*);
using DestroyFn = void (*)(overtake_plugin_handle*);

/// Bytes of the buffer create may write its reason into (the header promises at least
/// OVERTAKE_PLUGIN_MIN_ERROR_SIZE).
constexpr std::size_t kCreateErrorSize = 1024;
static_assert(kCreateErrorSize >= OVERTAKE_PLUGIN_MIN_ERROR_SIZE);

/// Below this, a version number is one of the first ABI's plain numbers (version 1 returned
/// 1), not major * 1000 + minor.
constexpr int kVersionBase = 1000;
static_assert(OVERTAKE_PLUGIN_ABI_VERSION ==
              OVERTAKE_PLUGIN_ABI_MAJOR * kVersionBase + OVERTAKE_PLUGIN_ABI_MINOR);

/// A version number as people write it: "2.1", or "1" for the first ABI's plain numbers.
std::string version_text(int v) {
  if (v < kVersionBase) return std::to_string(v);
  return std::to_string(v / kVersionBase) + "." + std::to_string(v % kVersionBase);
}

/// Refuses a plugin whose version this overtake cannot load, naming both versions and what
/// to do: another major version, or a newer minor one (whose structs may be longer than the
/// ones this side fills). An older minor is fine: it reads a prefix of what this side gives.
void check_version(const std::string& file, int v) {
  const std::string ours = version_text(OVERTAKE_PLUGIN_ABI_VERSION);
  const std::string head = file + ": built for plugin ABI version " + version_text(v) +
                           ", but this overtake speaks version " + ours;
  const std::string rebuild = "rebuild it against this overtake's overtake/planner_plugin.h";
  if (v <= 0) {
    throw PluginError(file + ": reports plugin ABI version " + std::to_string(v) +
                      ", which is no version (overtake_plugin_abi_version() must return "
                      "OVERTAKE_PLUGIN_ABI_VERSION)");
  }
  const int major = v < kVersionBase ? v : v / kVersionBase;
  const int minor = v < kVersionBase ? 0 : v % kVersionBase;
  if (major < OVERTAKE_PLUGIN_ABI_MAJOR) {
    throw PluginError(head + ", which no longer loads version " + std::to_string(major) +
                      " plugins: " + rebuild + " (see docs/planners.md for what changed)");
  }
  if (major > OVERTAKE_PLUGIN_ABI_MAJOR) {
    throw PluginError(head + ": use an overtake of plugin ABI version " + std::to_string(major) +
                      ", or " + rebuild);
  }
  if (minor > OVERTAKE_PLUGIN_ABI_MINOR) {
    throw PluginError(head + ", which is older: use an overtake of plugin ABI version " +
                      version_text(v) + " or later, or " + rebuild);
  }
}

/// The text of a C string the plugin gave, or `fallback` when it gave none.
/// The most of a plugin's reason that is kept: its text need not end within any buffer.
constexpr std::size_t kMaxReasonBytes = 4096;

/// A plugin's reason (or an exception's text) as overtake keeps it: at most kMaxReasonBytes,
/// and valid UTF-8 (a reason cut in the middle of a character, or in Latin-1, gets U+FFFD for
/// each stray byte), since it is written into JSON.
std::string text_or(const char* s, const char* fallback) {
  if (s == nullptr || *s == '\0') return fallback;
  const std::size_t n = ::strnlen(s, kMaxReasonBytes);
  std::string text = core::valid_utf8(std::string_view(s, n));
  if (n == kMaxReasonBytes) text += " [cut]";
  return text;
}

/// An open library and its functions; dlclose when the last owner goes.
struct Library {
  void* dl = nullptr;
  std::string label;  ///< "plugin NAME (PATH)", for messages
  CreateFn create = nullptr;
  PlanFn plan = nullptr;
  DestroyFn destroy = nullptr;

  Library() = default;
  Library(const Library&) = delete;
  Library& operator=(const Library&) = delete;
  ~Library() {
    if (dl != nullptr) ::dlclose(dl);
  }
};

/// Looks up one required function; PluginError naming it and the file when it is missing.
template <class Fn>
Fn symbol(void* dl, const char* name, const std::string& path) {
  ::dlerror();  // clear
  void* p = ::dlsym(dl, name);
  if (p == nullptr) {
    throw PluginError(path + ": not a planner plugin: the function " + name +
                      " is missing (see overtake/planner_plugin.h)");
  }
  return reinterpret_cast<Fn>(p);  // NOLINT(cppcoreguidelines-pro-type-reinterpret-cast): dlsym
}

/// How each call is checked and converted: one instance per run.
class PluginPolicy final : public planner::Policy {
 public:
  PluginPolicy(std::shared_ptr<const Library> lib, overtake_plugin_handle* handle)
      : lib_(std::move(lib)), handle_(handle), out_x_(kMaxPathPoints), out_y_(kMaxPathPoints) {}
  PluginPolicy(const PluginPolicy&) = delete;
  PluginPolicy& operator=(const PluginPolicy&) = delete;
  ~PluginPolicy() override {
    try {
      lib_->destroy(handle_);
    } catch (...) {  // NOLINT(bugprone-empty-catch): a destructor cannot report it
    }
  }

  core::PlanResult plan(const core::Telemetry& t) override {
    const overtake_telemetry in = to_c(t);
    overtake_path out{};
    out.struct_size = sizeof(overtake_path);
    out.next_x = out_x_.data();
    out.next_y = out_y_.data();
    out.capacity = out_x_.size();
    out.count = 0;
    out.error = nullptr;
    int status = 0;
    try {
      status = lib_->plan(handle_, &in, &out);
    } catch (const std::exception& e) {
      fail("threw an exception: " + text_or(e.what(), "(no text)"));
    } catch (...) {
      fail("threw an exception");
    }
    if (status != 0) {
      fail("failed (status " + std::to_string(status) +
           "): " + text_or(out.error, "no reason given"));
    }
    // Judged by this side's buffers: the plugin may have written over the struct's fields.
    if (out.next_x != out_x_.data() || out.next_y != out_y_.data()) {
      fail("replaced the path buffers instead of writing into them");
    }
    if (out.struct_size != sizeof(overtake_path)) {
      fail("wrote over the path's struct_size (overtake sets it, the plugin only reads it)");
    }
    if (out.count > out_x_.size()) {
      fail("answered " + std::to_string(out.count) + " points, more than the buffers' " +
           std::to_string(out_x_.size()));
    }
    std::vector<core::Vec2> path;
    path.reserve(out.count);
    for (std::size_t i = 0; i < out.count; ++i) {
      const core::Vec2 p{out_x_[i], out_y_[i]};
      if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
        fail("answered a non-finite point (index " + std::to_string(i) + ")");
      }
      path.push_back(p);
    }
    if (const auto problem = core::path_problem(path)) fail("answered a bad path: " + *problem);
    // The ABI carries points only: how the plugin found them is not for overtake to say.
    core::PlanResult result = core::normal_plan(std::move(path));
    result.status_known = false;
    return result;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw PluginError(lib_->label + ": " + what);
  }

  /// The telemetry in the original's units (yaw in degrees, speed in mph), rounded as the
  /// original sends them; the arrays live in this policy until the next call. An empty array
  /// is NULL, as the header allows: a plugin that reads one without looking at its count is
  /// then caught at once, not only when a vector happens to have no storage.
  overtake_telemetry to_c(const core::Telemetry& t) {
    overtake_telemetry c{};
    c.struct_size = sizeof(overtake_telemetry);
    c.x = t.ego.position.x;
    c.y = t.ego.position.y;
    c.s = t.ego.s_m;
    c.d = t.ego.d_m;
    c.yaw = core::wire_round(core::rad_to_deg(t.ego.yaw_rad));
    c.speed = core::wire_round(core::mps_to_mph(t.ego.speed_mps));
    prev_x_.clear();
    prev_y_.clear();
    for (const core::Vec2& p : t.previous_path) {
      prev_x_.push_back(p.x);
      prev_y_.push_back(p.y);
    }
    c.previous_path_x = prev_x_.empty() ? nullptr : prev_x_.data();
    c.previous_path_y = prev_y_.empty() ? nullptr : prev_y_.data();
    c.previous_path_count = prev_x_.size();
    c.end_path_s = t.end_path.s_m;
    c.end_path_d = t.end_path.d_m;
    cars_.clear();
    for (const core::CarObservation& car : t.cars) {
      cars_.insert(cars_.end(), {static_cast<double>(car.id), car.position.x, car.position.y,
                                 car.velocity_mps.x, car.velocity_mps.y, car.s_m, car.d_m});
    }
    // Rows of OVERTAKE_SF_COLUMNS doubles, back to back: the C side's `double (*)[7]`.
    c.sensor_fusion =
        cars_.empty()
            ? nullptr
            : reinterpret_cast<
                  const double(*)
                      [OVERTAKE_SF_COLUMNS]>(  // NOLINT(cppcoreguidelines-pro-type-reinterpret-cast)
                  cars_.data());
    c.sensor_fusion_count = t.cars.size();
    c.speed_mps = t.ego.speed_mps;  // 2.1
    return c;
  }

  std::shared_ptr<const Library> lib_;
  overtake_plugin_handle* handle_;
  std::vector<double> prev_x_, prev_y_;
  std::vector<double> cars_;  ///< sensor fusion rows, flat
  std::vector<double> out_x_, out_y_;
};

/// A policy for a plugin whose create failed: every plan fails with the reason, so that the
/// run ends as planner_failed (a bench goes on with its other runs).
class FailedPolicy final : public planner::Policy {
 public:
  explicit FailedPolicy(std::string why) : why_(std::move(why)) {}
  core::PlanResult plan(const core::Telemetry& /*telemetry*/) override { throw PluginError(why_); }

 private:
  std::string why_;
};

std::unique_ptr<planner::Policy> make_policy(const std::shared_ptr<const Library>& lib,
                                             const core::ReferenceLine& line,
                                             const planner::PlannerParams& params,
                                             const std::string* config_json) {
  std::vector<overtake_waypoint> waypoints;
  for (const core::Waypoint& w : line.map().waypoints) {
    waypoints.push_back({w.x_m, w.y_m, w.s_m, w.dx, w.dy});
  }
  overtake_plugin_setup setup{};
  setup.struct_size = sizeof(overtake_plugin_setup);
  setup.waypoints = waypoints.data();
  setup.waypoint_count = waypoints.size();
  setup.max_s = line.map().loop_length_m;
  setup.lane_count = params.road.lane_count;
  setup.lane_width = params.road.lane_width_m;
  setup.step_time = params.step_s;
  setup.config_json = config_json != nullptr ? config_json->c_str() : nullptr;
  std::array<char, kCreateErrorSize> error{};  // empty text, as the header promises
  overtake_plugin_handle* handle = nullptr;
  try {
    handle = lib->create(&setup, error.data(), error.size());
  } catch (const std::exception& e) {
    return std::make_unique<FailedPolicy>(
        lib->label + ": create threw an exception: " + text_or(e.what(), "(no text)"));
  } catch (...) {
    return std::make_unique<FailedPolicy>(lib->label + ": create threw an exception");
  }
  if (handle == nullptr) {
    error.back() = '\0';  // a reason that filled the buffer without its NUL is cut short
    return std::make_unique<FailedPolicy>(
        lib->label + ": create failed: " + text_or(error.data(), "no reason given"));
  }
  return std::make_unique<PluginPolicy>(lib, handle);
}

}  // namespace

LoadedPlugin load_plugin(const std::filesystem::path& path) {
  const std::string file = path.string();
  // A bare name would be searched on the library path: a plugin is always a file.
  const std::string open_as = path.has_parent_path() ? file : "./" + file;
  auto lib = std::make_shared<Library>();
  // RTLD_NODELETE: the code stays mapped after the last dlclose, so that a plugin's thread
  // still finishing after destroy, or a plan call abandoned because it never returns, runs
  // on instead of jumping into unmapped memory and taking the whole process down.
  lib->dl = ::dlopen(open_as.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
  if (lib->dl == nullptr) {
    const char* why = ::dlerror();
    throw PluginError(file + ": cannot load: " + text_or(why, "unknown dlopen error"));
  }
  // The version first: a plugin of another version may name its functions otherwise (version
  // 1 had overtake_plugin_info), and "built for version 1" says more than a missing function.
  const auto version = symbol<AbiVersionFn>(lib->dl, "overtake_plugin_abi_version", file);
  int v = 0;
  try {
    v = version();
  } catch (...) {
    throw PluginError(file + ": threw an exception while being loaded");
  }
  check_version(file, v);
  const auto info = symbol<InfoFn>(lib->dl, "overtake_plugin_get_info", file);
  lib->create = symbol<CreateFn>(lib->dl, "overtake_plugin_create", file);
  lib->plan = symbol<PlanFn>(lib->dl, "overtake_plugin_plan", file);
  lib->destroy = symbol<DestroyFn>(lib->dl, "overtake_plugin_destroy", file);

  LoadedPlugin loaded;
  try {
    const overtake_plugin_info* i = info();
    if (i == nullptr || i->name == nullptr || *i->name == '\0') {
      throw PluginError(file + ": overtake_plugin_info() gives no name");
    }
    loaded.name = i->name;
    loaded.summary = i->summary != nullptr ? i->summary : "";
  } catch (const PluginError&) {
    throw;
  } catch (...) {
    throw PluginError(file + ": threw an exception while being loaded");
  }
  lib->label = "plugin " + loaded.name + " (" + file + ")";
  std::shared_ptr<const Library> shared = std::move(lib);
  loaded.make = [shared](const core::ReferenceLine& line, const planner::PlannerParams& params) {
    return make_policy(shared, line, params, nullptr);
  };
  loaded.with_config = [shared](const std::string& config_json) -> planner::PolicyFactory {
    return [shared, config_json](const core::ReferenceLine& line,
                                 const planner::PlannerParams& params) {
      return make_policy(shared, line, params, &config_json);
    };
  };
  return loaded;
}

}  // namespace overtake::plugin
