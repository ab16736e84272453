#include "overtake/run/pages.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <set>
#include <thread>

#include "overtake/base/build_info.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/run/resources.hpp"
#include "overtake/view/page.hpp"

namespace overtake::run {

using base::json_text;
using base::kExitOk;
using base::overtake_version;
using base::read_file;
using base::same_file;
using base::UsageError;
using base::write_file_atomic;
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr auto kStopPoll = std::chrono::milliseconds(100);

}  // namespace

std::string_view embedded_page(std::string_view name) {
  const auto page = resources::embedded_file(name);
  if (!page) {
    // The only build without the pages is one configured so (cmake/Web.cmake).
    throw std::runtime_error("this build of overtake has no " + std::string(name) +
                             " page: it was made without the web pages (OVERTAKE_WEB=OFF); "
                             "`view`, `--live` and `bench --html` need a build with "
                             "OVERTAKE_WEB=ON");
  }
  return *page;
}

replay::ReplayHeader replay_header_for(const Track& track, const Config& config,
                                       const RunProvenance& p, double duration_s,
                                       const sim::Scenario* scenario,
                                       const sim::CheckpointInfo* from) {
  replay::ReplayProvenance rp;
  rp.policy = p.policy;
  rp.traffic = p.traffic;
  rp.seed = p.seed;
  rp.track = p.map_path == kBuiltinMapSource ? "default" : p.map_path;
  rp.duration_s = duration_s;
  rp.overtake_version = overtake_version();
  rp.config_hash = p.params_hash;
  if (scenario && scenario->cut && from) {
    replay::ReplayCutOrigin o;
    o.scenario = scenario->name;
    o.replay = scenario->cut->from_replay;
    o.policy = from->policy;
    o.traffic = from->traffic;
    o.seed = from->seed;
    o.at_s = scenario->cut->at_s;
    o.start_s = scenario->cut->start_s;
    o.incident = scenario->cut->incident;
    rp.cut_from = std::move(o);
  }
  return replay::make_replay_header(track.line, config.world, std::move(rp));
}

std::string replay_report_json(const sim::RunReport& report, const RunProvenance& provenance) {
  json j = report_to_json(report, provenance);
  j.erase("timing");
  return json_text(j);
}

std::shared_ptr<view::LiveView> start_live_view(const replay::ReplayHeader& header,
                                                const LiveOptions& live) {
  view::ViewServerOptions server;
  server.host = live.host;
  server.port = static_cast<std::uint16_t>(live.port);
  auto out = std::make_shared<view::LiveView>(embedded_page(kViewerPageName),
                                              replay::replay_header_json(header), server);
  if (live.on_listening) live.on_listening(out->url());
  return out;
}

std::string load_replay_for_view(const fs::path& replay, bool allow_partial, std::string* warning) {
  std::string bytes = read_file(replay, replay::kMaxReplayBytes);
  const replay::ReplayCheck check = replay::check_replay(bytes, replay.string());
  if (check.error.empty()) return bytes;
  if (!allow_partial || check.frames == 0) {
    throw std::runtime_error(check.error + (check.frames > 0 ? "\n  (--partial shows the " +
                                                                   std::to_string(check.frames) +
                                                                   " frames before the fault)"
                                                             : ""));
  }
  if (warning) *warning = check.error;
  return bytes;
}

void write_viewer_html(std::string_view replay_bytes, const fs::path& out,
                       std::string_view viewer_template, std::string_view name) {
  write_file_atomic(
      out, view::viewer_page(viewer_template, view::ViewerSource::embedded, replay_bytes, name));
}

int run_view(const ViewOptions& opts, const std::atomic<bool>& stop,
             const std::function<void(const std::string&)>& on_listening) {
  if (opts.port < 0 || opts.port > 65535) {
    throw UsageError("--port must be between 0 and 65535 (got " + std::to_string(opts.port) + ")");
  }
  if (opts.html && same_file(*opts.html, opts.replay)) {
    throw UsageError("--html " + opts.html->string() +
                     " is the replay itself; it would be overwritten by the page");
  }
  std::string warning;
  std::string bytes = load_replay_for_view(opts.replay, opts.partial, &warning);
  if (!warning.empty()) std::fprintf(stderr, "warning: %s\n", warning.c_str());
  const std::string_view page = embedded_page(kViewerPageName);
  if (opts.html) {
    const std::string html = view::viewer_page(page, view::ViewerSource::embedded, bytes,
                                               opts.replay.filename().string());
    write_file_atomic(*opts.html, html);
    if (!opts.quiet) {
      // The page's own size: the target may be a device (/dev/null) with none.
      std::printf("written: %s (%.1f MB, opens from disk)\n", opts.html->c_str(),
                  static_cast<double>(html.size()) / 1e6);
    }
    return kExitOk;
  }
  view::ViewContent content;
  content.page =
      view::viewer_page(page, view::ViewerSource::http, {}, opts.replay.filename().string());
  content.replay = std::make_shared<const std::string>(std::move(bytes));
  view::ViewServerOptions server_opts;
  server_opts.host = opts.host;
  server_opts.port = static_cast<std::uint16_t>(opts.port);
  view::ViewServer server(std::move(content), server_opts);
  if (!opts.quiet) {
    std::printf("serving %s at %s (Ctrl-C to stop)\n", opts.replay.c_str(), server.url().c_str());
    std::fflush(stdout);
  }
  if (on_listening) on_listening(server.url());
  while (!stop.load()) std::this_thread::sleep_for(kStopPoll);
  return kExitOk;
}

}  // namespace overtake::run
