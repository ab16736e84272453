// The protocol codec on one websocket text frame, read both ways the program reads: as the
// simulator's telemetry (`overtake serve`) and as a planner's reply (`overtake sim --planner`),
// with the framing helpers the session looks at first. The codec reports bad input in its
// results and never throws, so any exception is a finding. A reply that parses must also
// survive being written and read again unchanged (what `serve` writes, `sim` reads).

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "overtake/protocol/codec.hpp"

namespace protocol = overtake::protocol;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view frame(reinterpret_cast<const char*>(data), size);
  (void)protocol::split_packet(frame);
  (void)protocol::is_event(frame);
  (void)protocol::event_name(frame);
  (void)protocol::excerpt(frame);

  const auto telemetry = protocol::parse_telemetry(frame);
  if (telemetry && telemetry.value()) (void)protocol::format_telemetry(*telemetry.value());

  const auto reply = protocol::parse_reply(frame);
  if (reply && !reply.value().manual) {
    const auto again = protocol::parse_reply(protocol::format_control(reply.value().path));
    if (!again || again.value().path != reply.value().path) {
      std::fprintf(stderr, "a parsed control does not read back the same after format_control\n");
      std::abort();
    }
  }
  return 0;
}
