// Speed of the original protocol (README: "Figures"):
//   ./build/release/overtake_bench --benchmark_filter=Protocol
// Round trips per second over loop-back in lock-step against `serve` (walkthrough), and the
// cost of parsing and formatting one telemetry with 12 cars and a 50-point path.

#include <benchmark/benchmark.h>

#include <future>
#include <thread>

#include <boost/asio/io_context.hpp>

#include "overtake/protocol/client.hpp"
#include "overtake/protocol/codec.hpp"
#include "overtake/protocol/server.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/sim/world.hpp"

namespace {

using namespace overtake;

std::shared_ptr<const run::Track> track() {
  static const auto t = run::load_track(std::nullopt);
  return t;
}

// A telemetry on the default track, 30 s into a drive (every car placed), with a 50-point
// queue ahead of the ego.
core::Telemetry snapshot() {
  const auto t = track();
  sim::World world(t->map, t->line, run::default_config().world, sim::TrafficProfile::faithful, 1);
  const auto lane_path = [&](int n) {
    std::vector<core::Vec2> path;
    const double s0 = world.ego().frenet.s_m;
    for (int i = 1; i <= n; ++i) path.push_back(t->line.to_cartesian({s0 + 0.42 * i, 6.0}));
    return path;
  };
  world.apply_path(lane_path(1600));
  for (int i = 0; i < 1500; ++i) world.step();
  world.apply_path(lane_path(50));
  return world.telemetry();
}

void BM_ProtocolParseTelemetry(benchmark::State& state) {
  const core::Telemetry t = snapshot();
  const std::string text = protocol::format_telemetry(t);
  if (t.previous_path.size() != 50 || t.cars.size() != 12)
    state.SkipWithError("unexpected snapshot");
  for (auto _ : state) {
    auto r = protocol::parse_telemetry(text);
    benchmark::DoNotOptimize(r);
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(text.size()));
  state.SetLabel(std::to_string(text.size()) + " bytes, 12 cars, 50 points");
}
BENCHMARK(BM_ProtocolParseTelemetry);

void BM_ProtocolFormatTelemetry(benchmark::State& state) {
  const core::Telemetry t = snapshot();
  std::string text;
  for (auto _ : state) {
    text.clear();
    protocol::append_telemetry(text, t);
    benchmark::DoNotOptimize(text.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(text.size()));
}
BENCHMARK(BM_ProtocolFormatTelemetry);

void BM_ProtocolParseControl(benchmark::State& state) {
  const std::string text = protocol::format_control(snapshot().previous_path);
  for (auto _ : state) {
    auto r = protocol::parse_reply(text);
    benchmark::DoNotOptimize(r);
  }
  state.SetLabel("50 points");
}
BENCHMARK(BM_ProtocolParseControl);

// Lock-step round trips over loop-back: telemetry out, the walkthrough plans in `serve`,
// control back, path applied, 1-3 world steps. Items per second = round trips per second.
void BM_ProtocolRoundTrip(benchmark::State& state) {
  boost::asio::io_context ioc;
  protocol::PlannerSetup setup;
  setup.line = std::shared_ptr<const core::ReferenceLine>(track(), &track()->line);
  setup.params = run::default_config().planner;
  protocol::ServeOptions opts;
  opts.port = 0;
  opts.status_lines = false;
  opts.log = [](protocol::LogLevel, std::string_view) {};
  std::promise<std::uint16_t> bound;
  std::thread server([&] {
    protocol::run_server(ioc, setup, opts, [&](std::uint16_t p) { bound.set_value(p); });
  });
  const std::uint16_t port = bound.get_future().get();
  {
    protocol::ClientOptions client;
    client.log = opts.log;
    protocol::PlannerConnection connection(
        protocol::parse_planner_url("ws://127.0.0.1:" + std::to_string(port)).value(), client);
    protocol::RemotePlanner remote(connection, client);
    const auto t = track();
    sim::World world(t->map, t->line, run::default_config().world, sim::TrafficProfile::faithful,
                     1);
    int k = 0;
    for (auto _ : state) {
      world.apply_path(remote(world.telemetry()).path);
      for (int i = 0; i <= k; ++i) world.step();
      k = (k + 1) % 3;
    }
    connection.close();
  }
  ioc.stop();
  server.join();
  state.SetItemsProcessed(state.iterations());
  state.SetLabel("lock-step, walkthrough, items = round trips");
}
BENCHMARK(BM_ProtocolRoundTrip)->MinTime(2.0)->UseRealTime();

}  // namespace
