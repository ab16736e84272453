#pragma once
// C++ planner plugins: shared libraries built against the C ABI of
// include/overtake/planner_plugin.h, loaded with dlopen and wrapped as planner::Policy.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>

#include "overtake/planner/policy.hpp"

namespace overtake::plugin {

/// How many path points a plugin may answer per cycle (the capacity of its buffers).
inline constexpr std::size_t kMaxPathPoints = 10'000;

/// A plugin that cannot be loaded or used; the message names the file and what is wrong.
class PluginError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A loaded plugin: its name and a factory of policy instances (the library stays loaded as
/// long as the factory or any policy it made lives).
struct LoadedPlugin {
  std::string name;
  std::string summary;
  planner::PolicyFactory make;
  /// The factory of policies created with `config_json` as the setup's config_json (a JSON
  /// object of numbers by name: `overtake tune`'s parameters).
  std::function<planner::PolicyFactory(const std::string& config_json)> with_config;
};

/// Loads the plugin at `path` (RTLD_NODELETE: its code stays mapped for good, for the threads
/// it may leave finishing) and checks its version (the same major, a minor up to this
/// overtake's) and symbols. Throws PluginError.
/// The policies it makes throw PluginError from plan() when the plugin fails (a nonzero
/// status, an exception, a non-finite point, more points than its buffers hold), naming the
/// plugin and the reason: the run then ends as planner_failed.
[[nodiscard]] LoadedPlugin load_plugin(const std::filesystem::path& path);

}  // namespace overtake::plugin
