// The planner's answers to the simulator's frames, without sockets.

#include <chrono>
#include <cmath>
#include <exception>
#include <string>

#include "overtake/protocol/server.hpp"

namespace overtake::protocol {
namespace {

bool all_finite(const std::vector<core::Vec2>& path) {
  for (const core::Vec2 p : path) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) return false;
  }
  return true;
}

std::string bytes(std::size_t n) {
  return std::to_string(n) + (n == 1 ? " byte" : " bytes");
}

}  // namespace

PlannerSession::PlannerSession(std::unique_ptr<planner::Policy> policy, const Limits& limits,
                               std::size_t max_frame_bytes)
    : policy_(std::move(policy)), limits_(limits), max_frame_bytes_(max_frame_bytes) {}

FrameOutcome PlannerSession::handle(const Frame& frame) {
  FrameOutcome out;
  if (frame.binary) {
    out.warning = "binary frame of " + bytes(frame.size) + " ignored (the protocol is text only)";
    return out;
  }
  if (frame.oversized) {
    out.warning = "frame of " + bytes(frame.size) + " is larger than the limit of " +
                  bytes(max_frame_bytes_) + ", dropped: " + excerpt(frame.text.substr(0, 40)) +
                  "...";
    // The simulator waits for an answer to a telemetry, however broken.
    const auto name = event_name(frame.text);
    if (is_event(frame.text) && (!name || *name == "telemetry")) {
      out.reply = std::string(kManual);
      *out.warning += "; replied manual";
    }
    return out;
  }
  const Packet packet = split_packet(frame.text);
  switch (packet.type) {
    case PacketType::invalid:
      out.warning = frame.text.empty()
                        ? std::string("empty frame ignored")
                        : "frame that is not an Engine.IO packet ignored: " + excerpt(frame.text);
      return out;
    case PacketType::ping:  // the simulator's probe; answering it is allowed
      out.reply = "3" + std::string(packet.data);
      return out;
    case PacketType::pong:
      return out;
    case PacketType::open:
      out.note = "Engine.IO open packet ignored: " + excerpt(frame.text);
      return out;
    case PacketType::close:
      out.note = "the simulator closed its Engine.IO session (1)";
      return out;
    case PacketType::upgrade:
    case PacketType::noop:
      out.note = "Engine.IO packet ignored: " + excerpt(frame.text);
      return out;
    case PacketType::message:
      break;
  }
  if (packet.data.empty()) {
    out.warning = "empty Engine.IO message (4) ignored";
    return out;
  }
  switch (packet.data[0]) {
    case '0':
      out.note = "Socket.IO connect (40) ignored";
      return out;
    case '1':
      out.note = "the simulator left (41)";
      return out;
    case '2':
      return handle_event(frame.text);
    default:
      out.warning = "Socket.IO packet other than an event ignored: " + excerpt(frame.text);
      return out;
  }
}

FrameOutcome PlannerSession::handle_event(std::string_view text) {
  FrameOutcome out;
  // Every event the simulator sends is a telemetry and it waits for the answer; an event
  // that is clearly something else (e.g. a planner's control sent back) gets none.
  const auto name = event_name(text);
  if (name && *name != "telemetry") {
    out.warning = "event " + excerpt(*name) + " ignored (the simulator sends only telemetry)";
    return out;
  }
  auto parsed = parse_telemetry(text, limits_);
  if (!parsed) {
    out.warning = "bad telemetry: " + parsed.error() + "; replied manual";
    out.reply = std::string(kManual);
    return out;
  }
  if (!parsed.value()) {  // the null form: nothing advanced since the last telemetry
    out.reply = std::string(kManual);
    return out;
  }
  const core::Telemetry& telemetry = *parsed.value();
  out.ego = telemetry.ego;
  std::vector<core::Vec2> path;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    path = policy_->plan(telemetry).path;
  } catch (const std::exception& e) {
    out.warning =
        std::string("the planner failed on this telemetry (") + e.what() + "); replied manual";
    out.reply = std::string(kManual);
    return out;
  }
  out.plan_us =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  if (!all_finite(path)) {  // written as null, it would stop the original simulator for good
    out.warning = "the planner produced a non-finite path point; replied manual";
    out.reply = std::string(kManual);
    return out;
  }
  out.reply = format_control(path);
  out.planned = true;
  return out;
}

}  // namespace overtake::protocol
