// Config overrides (`--config FILE`): run::apply_config_text on top of the defaults, then the
// config's hash that every report carries. A bad file is refused with run::ConfigError naming
// the key; anything else is a finding.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "overtake/run/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    // Config{} is the shipped config/overtake.json (tests/run/config_test.cpp checks they are
    // equal); starting from it spares parsing the built-in file for every input.
    const overtake::run::Config config =
        overtake::run::apply_config_text(overtake::run::Config{}, text, "fuzz.json");
    (void)overtake::run::config_hash(config);
  } catch (const overtake::run::ConfigError&) {
  }
  return 0;
}
