#pragma once
// The view server: serves the viewer page at /, a replay at /replay.otr, and a run's records
// live over a websocket at /live (docs/replay.md). Boost.Beast, loopback by default.
//
// IO model: the server owns one io_context, run by one background thread started by the
// constructor; each connection is a coroutine on it. The run that feeds a live view runs on
// the caller's thread and hands records over through LiveFeed (a lock and shared chunks), so
// a slow or vanished browser never holds up the run.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "overtake/replay/replay.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/view/page.hpp"

namespace overtake::view {

/// The records of a run as it goes, for websocket viewers. One thread publishes, the
/// server's thread reads; every chunk is kept (a viewer that comes late gets the whole run).
class LiveFeed {
 public:
  explicit LiveFeed(std::string header_json);
  /// The header JSON, the first (text) message of every viewer.
  [[nodiscard]] const std::string& header_json() const { return header_json_; }
  /// Adds whole records (kind, length, payload), in order.
  void publish(std::string records);
  /// No more records will come (after the end record).
  void close();

  /// What a viewer that has sent chunks [0, from) gets next.
  struct Next {
    std::vector<std::shared_ptr<const std::string>> chunks;
    bool closed = false;  ///< and nothing will follow these chunks
  };
  [[nodiscard]] Next next(std::size_t from) const;

 private:
  std::string header_json_;
  mutable std::mutex mu_;
  std::vector<std::shared_ptr<const std::string>> chunks_;
  bool closed_ = false;
};

/// A run observer that encodes the run into a LiveFeed, publishing about every 0.1 s of
/// simulated time. It does not pace the run: a live run is paced by its own clock
/// (sim::RunOptions::pace).
class LiveRecorder final : public sim::RunObserver {
 public:
  explicit LiveRecorder(LiveFeed& feed);
  void on_frame(const sim::Frame& frame, std::span<const sim::Incident> new_incidents) override;
  void on_path(std::span<const core::Vec2> path) override;
  /// Publishes what is pending and the end record (the run's report, JSON), and closes the
  /// feed.
  void finish(std::string_view report_json);

 private:
  void publish();
  LiveFeed& feed_;
  replay::ReplayEncoder encoder_;
  std::string pending_;
  std::optional<long> first_step_;
  long last_publish_step_ = 0;
};

/// What the server serves.
struct ViewContent {
  std::string page;                           ///< GET /: the viewer page, filled
  std::shared_ptr<const std::string> replay;  ///< GET /replay.otr, when set
  std::shared_ptr<const LiveFeed> live;       ///< the websocket /live, when set
};

/// What a request target names.
enum class ViewResource { none, page, replay, live };

/// How the server routes a request target: its path (the target without its query) and what
/// that path names in `content` (the page at / and /index.html, the replay at kReplayUrlPath
/// and the live feed at kLiveUrlPath when `content` has them; the live feed is served to a
/// websocket upgrade only). Pure, so that tests and the fuzzer reach it without a socket.
struct ViewRoute {
  ViewResource resource = ViewResource::none;
  std::string_view path;  ///< a part of the target
};
[[nodiscard]] ViewRoute route_target(std::string_view target, const ViewContent& content);

/// Whether a request's Host header names this server, so that a page from elsewhere that
/// reaches it through DNS rebinding (its own name made to resolve to this machine) is
/// refused: `localhost`, `127.0.0.1` or `[::1]`, or `bound_host` (the address or name the
/// server was told to listen on), each with any port or none, names compared without case.
/// When bound to every address (`0.0.0.0`, `::`), any address literal is accepted too: only
/// a name can be rebound. Pure, for tests and the fuzzer.
[[nodiscard]] bool host_allowed(std::string_view host, std::string_view bound_host);

/// Whether a websocket request's Origin header is the origin of the page this server serves
/// at `host` (the request's own Host header): `http://` and the same name and port (80 when
/// absent). Pure, for tests and the fuzzer.
[[nodiscard]] bool same_origin(std::string_view origin, std::string_view host);

/// Whether `name` is one of the loopback names a Host may always give (`localhost`,
/// `127.0.0.1`, `[::1]`), compared without case.
[[nodiscard]] bool is_loopback_name(std::string_view name);

/// A host as it appears in a URL or a Host header: an IPv6 address in brackets.
[[nodiscard]] std::string host_for_url(const std::string& host);

/// Where to listen.
struct ViewServerOptions {
  std::string host = "127.0.0.1";  ///< loopback by default: the page is for this machine
  std::uint16_t port = 8080;       ///< 0: any free port (see ViewServer::port)
};

/// Serves ViewContent over HTTP/1.1 (GET and HEAD; other paths get 404).
class ViewServer {
 public:
  /// Listens, then serves on a background thread. Throws ViewError when it cannot listen
  /// (a port in use, an address that is not this machine's, ...), saying which and what to do.
  ViewServer(ViewContent content, const ViewServerOptions& options);
  /// Stops serving (open connections are dropped) and joins the thread.
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  /// The port it listens on (the one chosen when options.port was 0).
  [[nodiscard]] std::uint16_t port() const;
  /// The page's address, e.g. http://127.0.0.1:8080/.
  [[nodiscard]] std::string url() const;
  /// Stops serving; idempotent.
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A live view of a run: the feed, the recorder (the run's observer) and the server.
class LiveView {
 public:
  /// `page_template`: the viewer page with its placeholders; `header_json`: the replay
  /// header. Throws ViewError when the page or the server cannot be set up.
  LiveView(std::string_view page_template, std::string header_json,
           const ViewServerOptions& options);
  [[nodiscard]] sim::RunObserver& observer() { return recorder_; }
  /// Sends the end record and closes the feed; the page stays served.
  void finish(std::string_view report_json) { recorder_.finish(report_json); }
  [[nodiscard]] std::string url() const { return server_->url(); }
  [[nodiscard]] std::uint16_t port() const { return server_->port(); }

 private:
  std::shared_ptr<LiveFeed> feed_;
  LiveRecorder recorder_;
  std::unique_ptr<ViewServer> server_;
};

}  // namespace overtake::view
