#include "overtake/app/viewer.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <set>
#include <thread>

#include "overtake/app/bench.hpp"
#include "overtake/app/build_info.hpp"
#include "overtake/app/cli.hpp"
#include "overtake/app/config.hpp"
#include "overtake/app/io.hpp"
#include "overtake/app/resources.hpp"
#include "overtake/eval/summary.hpp"
#include "overtake/view/page.hpp"

namespace overtake::app {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr const char* kBuiltinMapSource = "builtin:default";
constexpr auto kStopPoll = std::chrono::milliseconds(100);

// `to` relative to the folder `from_dir`, with forward slashes (a link in a page).
std::string link_between(const fs::path& from_dir, const fs::path& to) {
  const fs::path rel = fs::absolute(to).lexically_normal().lexically_relative(
      fs::absolute(from_dir).lexically_normal());
  return rel.generic_string();
}

}  // namespace

std::string overtake_version() {
  return std::string(project_version()) + "+" + std::string(build_revision());
}

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

std::string bench_replay_name(const std::string& policy, const std::string& traffic,
                              std::uint64_t seed) {
  return policy + "-" + traffic + "-seed" + std::to_string(seed) + ".otr";
}

json bench_report_object(const fs::path& bench_out, const fs::path& html_dir) {
  json out;
  out = read_json_file(bench_out / "bench.json");
  const std::vector<json> runs = load_bench_runs(bench_out);
  json with_links = json::array();
  for (json r : runs) {
    const fs::path otr = bench_out / kReplaysFolder /
                         bench_replay_name(r["config"]["policy"].get<std::string>(),
                                           r["config"]["traffic"].get<std::string>(),
                                           r["config"]["seed"].get<std::uint64_t>());
    fs::path page = otr;
    page.replace_extension(".html");
    r["replay"] = fs::exists(page) ? json(link_between(html_dir, page)) : json(nullptr);
    with_links.push_back(std::move(r));
  }
  out["runs"] = std::move(with_links);
  BenchSummary summary = summarize_bench(runs, out.at("policies").get<std::vector<std::string>>(),
                                         out.at("traffic").get<std::vector<std::string>>(),
                                         (bench_out / "runs.jsonl").string());
  out["summary"] = std::move(summary.rows);
  out["verdicts"] = eval::verdict_method(eval::family_size(summary.pairs));
  out["pairs"] = std::move(summary.pairs);
  return out;
}

std::vector<fs::path> write_bench_report(const fs::path& bench_out, const fs::path& html,
                                         std::string_view report_template,
                                         std::string_view viewer_template) {
  std::vector<fs::path> pages;
  const fs::path replays = bench_out / kReplaysFolder;
  std::error_code ec;
  if (fs::is_directory(replays, ec)) {
    std::set<fs::path> otrs;
    for (const auto& entry : fs::directory_iterator(replays)) {
      if (entry.path().extension() == ".otr") otrs.insert(entry.path());
    }
    for (const fs::path& otr : otrs) {
      fs::path page = otr;
      page.replace_extension(".html");
      std::string warning;
      std::string bytes;
      try {
        bytes = load_replay_for_view(otr, true, &warning);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "bench: %s: not linked from the report: %s\n", otr.c_str(), e.what());
        fs::remove(page, ec);
        continue;
      }
      if (!warning.empty()) std::fprintf(stderr, "bench: warning: %s\n", warning.c_str());
      write_viewer_html(bytes, page, viewer_template, otr.filename().string());
      pages.push_back(page);
    }
  }
  fs::path dir = html.parent_path();
  if (dir.empty()) dir = ".";
  const json object = bench_report_object(bench_out, dir);
  write_file_atomic(html, view::report_page(report_template, json_text(object)));
  return pages;
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

}  // namespace overtake::app
