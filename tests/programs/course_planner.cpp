// A planner program that behaves like the ones written for the original simulator: it listens
// on the fixed port 4567 on every address, serves one simulator connection at a time, prints
// a line for every message it gets, and crashes (abort) when the simulator disconnects. It
// drives with the built-in walkthrough policy, through the protocol's codec.
//
// For the tests of `--planner-cmd`, it can also misbehave on purpose:
//   --crash-after N     abort after answering N telemetries
//   --hang-after N      stop answering after N telemetries (and sleep)
//   --never-listen      never open the port (sleep)
//   --exit-at-start     exit at once with status 3
//   --port P            listen on P instead of 4567
//   --speed-mps V       drive at V m/s (the walkthrough policy's target speed; a parameter
//                       for the tests of `overtake tune`)
//   --random            not deterministic: each new point of an answer moves by up to 0.5 m,
//                       drawn from the operating system's random numbers (as a planner whose
//                       answers depend on threads, clocks or random numbers)

// GCC 12 may report a false maybe-uninitialized inside Beast's HTTP parser (boost::optional)
// depending on inlining (seen with the sanitizers), as in src/protocol/server.cpp.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#pragma GCC diagnostic pop
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <thread>

#include "overtake/planner/policy.hpp"
#include "overtake/protocol/codec.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"

namespace net = boost::asio;
namespace websocket = boost::beast::websocket;
using tcp = net::ip::tcp;

namespace {

struct Args {
  long crash_after = -1;
  long hang_after = -1;
  bool never_listen = false;
  bool exit_at_start = false;
  bool random = false;
  unsigned short port = 4567;
  double speed_mps = 0.0;  ///< 0: the config's
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&] { return i + 1 < argc ? std::atol(argv[++i]) : 0L; };
    if (arg == "--crash-after") {
      a.crash_after = value();
    } else if (arg == "--hang-after") {
      a.hang_after = value();
    } else if (arg == "--never-listen") {
      a.never_listen = true;
    } else if (arg == "--exit-at-start") {
      a.exit_at_start = true;
    } else if (arg == "--random") {
      a.random = true;
    } else if (arg == "--port") {
      a.port = static_cast<unsigned short>(value());
    } else if (arg == "--speed-mps" && i + 1 < argc) {
      a.speed_mps = std::atof(argv[++i]);
    } else {
      std::fprintf(stderr, "course_planner: unknown argument %s\n", arg.c_str());
      std::exit(2);
    }
  }
  return a;
}

[[noreturn]] void sleep_forever() {
  for (;;) std::this_thread::sleep_for(std::chrono::seconds(60));
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  std::printf("course_planner: starting\n");
  std::fflush(stdout);
  if (args.exit_at_start) return 3;
  if (args.never_listen) sleep_forever();

  const auto track = overtake::run::load_track(std::nullopt);
  auto config = overtake::run::default_config();
  if (args.speed_mps > 0.0) config.planner.walkthrough.target_speed_mps = args.speed_mps;
  net::io_context ioc;
  tcp::acceptor acceptor(ioc, tcp::endpoint(net::ip::address_v4::any(), args.port));
  std::printf("Listening to port %u\n", static_cast<unsigned>(args.port));
  std::fflush(stdout);
  for (;;) {
    tcp::socket socket(ioc);
    acceptor.accept(socket);
    std::printf("Connected!!!\n");
    websocket::stream<tcp::socket> ws(std::move(socket));
    ws.accept();
    auto policy = overtake::planner::make_policy("walkthrough", track->line, config.planner);
    long answered = 0;
    for (;;) {
      boost::beast::flat_buffer buffer;
      boost::system::error_code ec;
      ws.read(buffer, ec);
      if (ec) {
        // As the course's programs do when the simulator goes away.
        std::printf("Disconnected\n");
        std::fflush(stdout);
        std::abort();
      }
      const std::string text = boost::beast::buffers_to_string(buffer.data());
      std::printf("%s\n", text.substr(0, 200).c_str());  // a lot of output, as they print
      const auto event = overtake::protocol::parse_telemetry(text);
      std::string reply(overtake::protocol::kManual);
      if (event && event.value()) {
        if (args.hang_after >= 0 && answered >= args.hang_after) sleep_forever();
        if (args.crash_after >= 0 && answered >= args.crash_after) std::abort();
        auto plan = policy->plan(*event.value());
        if (args.random) {
          std::random_device device;
          std::uniform_real_distribution<double> shift(-0.5, 0.5);
          const std::size_t kept = event.value()->previous_path.size();
          for (std::size_t i = kept; i < plan.path.size(); ++i) plan.path[i].y += shift(device);
        }
        reply = overtake::protocol::format_control(plan.path);
        ++answered;
      }
      ws.text(true);
      ws.write(net::buffer(reply));
    }
  }
}
