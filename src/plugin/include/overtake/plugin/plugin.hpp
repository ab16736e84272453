#pragma once
// C++ planner plugins: shared libraries built against the C ABI of
// include/overtake/planner_plugin.h, loaded with dlopen and wrapped as planner::Policy.

#include <filesystem>
#include <stdexcept>
#include <string>

#include "overtake/planner/policy.hpp"

namespace overtake::plugin {

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
};

/// Loads the plugin at `path` and checks its version and symbols. Throws PluginError.
[[nodiscard]] LoadedPlugin load_plugin(const std::filesystem::path& path);

}  // namespace overtake::plugin
