// Map files (`drive --map`, `serve --map`, ...): core::parse_map, then the reference line that
// every command builds from the map it read (core::ReferenceLine). Both refuse a bad map with
// core::MapError, which says what is wrong and where; anything else (another exception, a
// sanitizer report, a hang) is a finding.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "overtake/core/map.hpp"
#include "overtake/core/reference_line.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const overtake::core::Map map = overtake::core::parse_map(text, "fuzz.csv");
    const overtake::core::ReferenceLine line(map);
  } catch (const overtake::core::MapError&) {
  }
  return 0;
}
