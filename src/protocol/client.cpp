// The simulator's side of the protocol: the lock-step PlannerFn (RemotePlanner) and the
// real-time loop, over a PlannerConnection (connection.cpp).

#include "overtake/protocol/client.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <deque>
#include <thread>

namespace overtake::protocol {
namespace {

// How often a wait for the planner looks at the stop flag (Ctrl-C).
constexpr auto kStopPoll = std::chrono::milliseconds(50);
// The least time finish() waits for a late reply after the run.
constexpr auto kLateReplyWait = std::chrono::milliseconds(100);
constexpr const char* kOutOfStep = "out of step: the planner replied twice to one telemetry";

}  // namespace

std::string seconds_text(std::chrono::milliseconds ms) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", static_cast<double>(ms.count()) / 1000.0);
  return buf;
}

// ---- what the planner sent --------------------------------------------------------------

namespace {

// A frame from the planner, sorted.
struct Sorted {
  enum Kind { reply, ping, pong, ignore, fatal } kind = ignore;
  std::string text;  // reply: the frame; ping: the pong to send; pong: its payload;
                     // ignore: a note; fatal: why
};

Sorted sort_planner_frame(const ReceivedFrame& f) {
  if (f.pong) return {Sorted::pong, f.text};
  if (f.binary) {
    return {Sorted::fatal,
            "malformed reply: a binary frame of " + std::to_string(f.text.size()) + " bytes"};
  }
  const Packet p = split_packet(f.text);
  switch (p.type) {
    case PacketType::invalid:
      return {Sorted::fatal, "malformed reply: not an Engine.IO packet: " + excerpt(f.text)};
    case PacketType::ping:
      return {Sorted::ping, "3" + std::string(p.data)};
    case PacketType::close:
      return {Sorted::fatal, "the planner closed its session (1)"};
    case PacketType::pong:
    case PacketType::open:
    case PacketType::upgrade:
    case PacketType::noop:
      return {Sorted::ignore, "ignored a packet from the planner: " + excerpt(f.text)};
    case PacketType::message:
      break;
  }
  if (!p.data.empty() && p.data[0] == '2') return {Sorted::reply, f.text};
  if (!p.data.empty() && p.data[0] == '0')
    return {Sorted::ignore, "ignored the planner's Socket.IO connect (40)"};
  if (!p.data.empty() && p.data[0] == '1') return {Sorted::fatal, "the planner left (41)"};
  return {Sorted::fatal, "malformed reply: not a Socket.IO event: " + excerpt(f.text)};
}

const LogFn& log_of(const ClientOptions& o) {
  static const LogFn fallback = stderr_log(false);
  return o.log ? o.log : fallback;
}

// A reply as a plan: the protocol carries points only, so how the planner found them (its
// plan status) is unknown, not normal.
core::PlanResult remote_plan(std::vector<core::Vec2> path) {
  core::PlanResult plan = core::normal_plan(std::move(path));
  plan.status_known = false;
  return plan;
}

}  // namespace

// ---- lock-step --------------------------------------------------------------------------

RemotePlanner::RemotePlanner(PlannerConnection& connection, const ClientOptions& options)
    : connection_(connection), options_(options) {}

// The next frame by `deadline`, looking at the stop flag now and then (a signal does not
// interrupt the wait itself).
std::optional<ReceivedFrame> RemotePlanner::receive(Clock::time_point deadline) {
  for (;;) {
    if (options_.stop && options_.stop->load(std::memory_order_relaxed)) {
      stopped_ = true;
      throw sim::PlannerFailure("stopped");
    }
    auto frame = connection_.receive(std::min(deadline, Clock::now() + kStopPoll));
    if (frame || Clock::now() >= deadline) return frame;
  }
}

// The bounds on the number of replies (see RemotePlanner in the header).
void RemotePlanner::count_reply(const ReceivedFrame& f) {
  ++replies_;
  if (replies_ > sent_) {
    throw sim::PlannerFailure(std::string(kOutOfStep) + " (" + std::to_string(replies_) +
                              " replies to " + std::to_string(sent_) +
                              " telemetries; the last: " + excerpt(f.text, 40) + ")");
  }
}

void RemotePlanner::count_pong(const std::string& payload) {
  long j = 0;
  const auto r = std::from_chars(payload.data(), payload.data() + payload.size(), j);
  if (r.ec != std::errc{} || r.ptr != payload.data() + payload.size() || j < 1 || j > sent_)
    return;  // not one of ours: an unasked pong (a heartbeat) is allowed
  last_pong_ = std::max(last_pong_, j);
  if (replies_ > j) {
    throw sim::PlannerFailure(std::string(kOutOfStep) + " (" + std::to_string(replies_) +
                              " replies came before its pong to the ping that followed telemetry " +
                              std::to_string(j) + ")");
  }
}

// A frame that came while no telemetry was waiting for its reply.
void RemotePlanner::take_unasked(const ReceivedFrame& f, bool after_run) {
  const Sorted s = sort_planner_frame(f);
  switch (s.kind) {
    case Sorted::reply:
      count_reply(f);
      return;
    case Sorted::pong:
      count_pong(s.text);
      return;
    case Sorted::ping:
      if (!after_run) connection_.send(s.text, Clock::now() + options_.reply_timeout);
      return;
    case Sorted::ignore:
      log_of(options_)(LogLevel::info, s.text);
      return;
    case Sorted::fatal:
      if (!after_run) throw sim::PlannerFailure(s.text);
      log_of(options_)(LogLevel::info, "after the run: " + s.text);
      return;
  }
}

core::PlanResult RemotePlanner::operator()(const core::Telemetry& telemetry) {
  const LogFn& log = log_of(options_);
  try {
    // Anything that came in since the last reply was not asked for.
    for (const ReceivedFrame& f : connection_.take_arrived()) take_unasked(f, false);

    buffer_.clear();
    append_telemetry(buffer_, telemetry);
    const auto sent_at = Clock::now();
    const auto deadline = sent_at + options_.reply_timeout;
    connection_.send(buffer_, deadline);
    ++sent_;
    connection_.ping(std::to_string(sent_), deadline);
    for (;;) {
      const auto frame = receive(deadline);
      if (!frame) {
        throw sim::PlannerFailure("the planner stalled: no reply within " +
                                  seconds_text(options_.reply_timeout));
      }
      const Sorted s = sort_planner_frame(*frame);
      if (s.kind == Sorted::fatal) throw sim::PlannerFailure(s.text);
      if (s.kind == Sorted::pong) {
        count_pong(s.text);
        continue;
      }
      if (s.kind == Sorted::ignore) {
        log(LogLevel::info, s.text);
        continue;
      }
      if (s.kind == Sorted::ping) {
        connection_.send(s.text, deadline);
        continue;
      }
      count_reply(*frame);
      longest_round_trip_ = std::max(longest_round_trip_, Clock::now() - sent_at);
      auto reply = parse_reply(frame->text, options_.limits);
      if (!reply) throw sim::PlannerFailure("malformed reply: " + reply.error());
      if (reply.value().manual) {
        if (!manual_noted_) {
          log(LogLevel::info,
              "the planner answered a full telemetry with manual: the queued path is kept");
          manual_noted_ = true;
        }
        return remote_plan(telemetry.previous_path);
      }
      return remote_plan(std::move(reply).value().path);
    }
  } catch (const ConnectionError& e) {
    throw sim::PlannerFailure(e.what());
  }
}

std::string RemotePlanner::finish() {
  if (sent_ == 0) return {};
  try {
    for (const ReceivedFrame& f : connection_.take_arrived()) take_unasked(f, true);
    // The last pong says what the planner had sent when it read the last telemetry.
    const auto deadline = Clock::now() + options_.reply_timeout;
    while (last_pong_ < sent_) {
      const auto frame = receive(deadline);
      if (!frame) {
        log_of(options_)(LogLevel::warning,
                         "the planner did not answer our last websocket ping (RFC 6455 requires "
                         "a pong): a second reply to one telemetry may have gone unnoticed");
        break;
      }
      take_unasked(*frame, true);
    }
    // A copy sent from a timer or another thread may come after the last pong.
    const auto wait = std::min<Clock::duration>(
        options_.reply_timeout, std::max<Clock::duration>(kLateReplyWait, 2 * longest_round_trip_));
    const auto until = Clock::now() + wait;
    while (const auto frame = receive(until)) take_unasked(*frame, true);
  } catch (const sim::PlannerFailure& e) {
    return stopped_ ? std::string() : std::string(e.what());
  } catch (const ConnectionError&) {  // gone after the run: nothing more can come
  }
  return {};
}

sim::RunReport run_lock_step(sim::World& world, PlannerConnection& connection,
                             const ClientOptions& options, sim::RunOptions run) {
  RemotePlanner remote(connection, options);
  run.clock = sim::CycleClock::round_trip;
  sim::RunReport report = sim::run_drive(
      world, [&remote](const core::Telemetry& t) { return remote(t); }, run);
  if (report.outcome.end == sim::RunEnd::completed) {
    const std::string why = remote.finish();
    if (!why.empty()) report.outcome = {sim::RunEnd::planner_failed, world.time_s(), why};
  }
  return report;
}

// ---- real time --------------------------------------------------------------------------

sim::RunReport run_realtime(sim::World& world, PlannerConnection& connection,
                            const ClientOptions& options, sim::RunOptions run_options) {
  const LogFn& log = log_of(options);
  run_options.pace = sim::Pace::real_time;
  run_options.clock = sim::CycleClock::round_trip;
  sim::Stepper run(world, run_options);

  std::string buffer;
  bool awaiting = false;       // a telemetry is out and unanswered
  bool awaiting_full = false;  // ... and it was a full one
  long last_full_step = -1;
  Clock::time_point sent_at;

  const auto send_telemetry = [&](bool full) {
    sent_at = Clock::now();
    if (full) {
      run.checkpoint_if_due();
      buffer.clear();
      append_telemetry(buffer, run.telemetry());
      last_full_step = world.steps();
    }
    connection.send(full ? std::string_view(buffer) : kNullTelemetry,
                    sent_at + options.reply_timeout);
    awaiting = true;
    awaiting_full = full;
  };

  try {
    send_telemetry(true);
    while (!run.finished()) {
      if (run.stop_requested()) {
        run.end(sim::RunEnd::stopped);
        break;
      }
      // The physics: every step that is due, whatever the planner is doing.
      bool stepped = false;
      while (!run.finished() && Clock::now() >= run.next_step_due()) {
        run.step();
        stepped = true;
      }
      if (run.finished()) break;
      if (!awaiting && stepped) send_telemetry(true);
      const auto reply_deadline = sent_at + options.reply_timeout;
      if (awaiting && Clock::now() >= reply_deadline) {
        throw sim::PlannerFailure("the planner stalled: no reply within " +
                                  seconds_text(options.reply_timeout));
      }

      const auto frame = connection.receive(awaiting ? std::min(run.next_step_due(), reply_deadline)
                                                     : run.next_step_due());
      if (!frame) continue;
      const Sorted s = sort_planner_frame(*frame);
      if (s.kind == Sorted::fatal) throw sim::PlannerFailure(s.text);
      if (s.kind == Sorted::pong) continue;  // unasked: a heartbeat, allowed by RFC 6455
      if (s.kind == Sorted::ignore) {
        log(LogLevel::info, s.text);
        continue;
      }
      if (s.kind == Sorted::ping) {
        connection.send(s.text, Clock::now() + options.reply_timeout);
        continue;
      }
      if (!awaiting) {
        log(LogLevel::warning,
            "the planner replied twice to one telemetry; the extra reply is ignored: " +
                excerpt(frame->text, 40));
        continue;
      }
      auto reply = parse_reply(frame->text, options.limits);
      if (!reply) throw sim::PlannerFailure("malformed reply: " + reply.error());
      awaiting = false;
      std::optional<double> round_trip_us;
      if (awaiting_full) {
        round_trip_us = std::chrono::duration<double, std::micro>(Clock::now() - sent_at).count();
      }
      if (!reply.value().manual) {
        run.apply(remote_plan(std::move(reply).value().path), round_trip_us,
                  round_trip_us.value_or(0.0));
      } else if (round_trip_us) {
        run.count_cycle(remote_plan({}), *round_trip_us, *round_trip_us);
      }
      // Next telemetry: full when anything stepped; null once when nothing did; after the
      // answer to a null one, the next step sends it.
      if (world.steps() > last_full_step) {
        send_telemetry(true);
      } else if (awaiting_full) {
        send_telemetry(false);
      }
    }
  } catch (const ConnectionError& e) {
    run.end(sim::RunEnd::planner_failed, e.what());
  } catch (const sim::PlannerFailure& e) {
    run.end(sim::RunEnd::planner_failed, e.what());
  }
  return run.report();
}

}  // namespace overtake::protocol
