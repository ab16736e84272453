// Scenario files (`drive --scenario FILE`): run::parse_scenario_text on the default road. A bad
// file is refused with run::ConfigError naming the key; anything else is a finding.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "overtake/run/config.hpp"
#include "overtake/run/scenario_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    (void)overtake::run::parse_scenario_text(text, "fuzz.json", overtake::core::RoadParams{});
  } catch (const overtake::run::ConfigError&) {
  }
  return 0;
}
