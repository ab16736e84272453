// Replay files (.otr): replay::check_replay, which `overtake view` runs on the file it is given
// and which reports every fault in its result, never by throwing; and replay::parse_replay, the
// reader that keeps the records, which refuses a bad file with replay::ReplayError. Anything else
// (another exception, a sanitizer report, a hang) is a finding.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "overtake/replay/replay.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  (void)overtake::replay::check_replay(bytes, "fuzz.otr");
  try {
    (void)overtake::replay::parse_replay(bytes, "fuzz.otr");
  } catch (const overtake::replay::ReplayError&) {
  }
  return 0;
}
