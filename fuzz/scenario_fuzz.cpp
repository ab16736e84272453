// Scenario files (`drive --scenario FILE`): app::parse_scenario_text on the default road. A bad
// file is refused with app::ConfigError naming the key; anything else is a finding.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "overtake/app/config.hpp"
#include "overtake/app/scenario_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    (void)overtake::app::parse_scenario_text(text, "fuzz.json", overtake::core::RoadParams{});
  } catch (const overtake::app::ConfigError&) {
  }
  return 0;
}
