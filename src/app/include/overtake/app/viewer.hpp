#pragma once
// Replays and pages for the command line: the replay header of a run, the viewer page of a
// replay (`view --html`), the live view of a run (`--live`), and the bench report page
// (`bench --html`). The pages are the ones embedded in the binary (web/, see
// docs/replay.md); functions that fill a page also take it as an argument, for tests.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/app/commands.hpp"
#include "overtake/app/report.hpp"
#include "overtake/replay/replay.hpp"
#include "overtake/view/server.hpp"

namespace overtake::app {

inline constexpr std::string_view kViewerPageName = "viewer.html";
inline constexpr std::string_view kReportPageName = "report.html";
/// Folder of a bench's recorded replays, inside its --out folder.
inline constexpr std::string_view kReplaysFolder = "replays";

/// This build's version, e.g. "0.1.0+c0733af12345" (the git revision it was built from).
[[nodiscard]] std::string overtake_version();

/// An embedded page (kViewerPageName or kReportPageName). Throws std::runtime_error when
/// this build has none (configured with OVERTAKE_WEB=OFF), saying so.
[[nodiscard]] std::string_view embedded_page(std::string_view name);

/// The replay header of a run: the track's lane lines, the config's limits, the provenance.
/// For a cut scenario (`cut` set) the header says where it was cut from (`from`: the
/// checkpoint's info).
[[nodiscard]] replay::ReplayHeader replay_header_for(const Track& track, const Config& config,
                                                     const RunProvenance& provenance,
                                                     double duration_s,
                                                     const sim::Scenario* scenario = nullptr,
                                                     const sim::CheckpointInfo* from = nullptr);

/// The `end` record of a replay: the report JSON without `timing` (deterministic).
[[nodiscard]] std::string replay_report_json(const sim::RunReport& report,
                                             const RunProvenance& provenance);

/// Starts the live view of a run and calls live.on_listening with its address. (The run
/// itself is paced: sim::RunOptions::pace.) Throws view::ViewError (a port in use, ...).
[[nodiscard]] std::shared_ptr<view::LiveView> start_live_view(const replay::ReplayHeader& header,
                                                              const LiveOptions& live);

/// Reads and checks a replay file: its bytes, or std::runtime_error naming the file and the
/// fault. With `allow_partial`, a replay whose body is cut short or damaged after some good
/// records is accepted (the page shows those records with a warning); `warning` then says
/// what is wrong.
[[nodiscard]] std::string load_replay_for_view(const std::filesystem::path& replay,
                                               bool allow_partial, std::string* warning = nullptr);

/// Writes the self-contained viewer page of `replay_bytes` to `out` (atomically); `name` is
/// the replay's file name (for the page's cut command).
void write_viewer_html(std::string_view replay_bytes, const std::filesystem::path& out,
                       std::string_view viewer_template, std::string_view name = {});

/// The bench report's data (docs/replay.md): bench.json's object with "runs" (each with
/// "replay": a link relative to `html_dir`, or null) and "summary". `replay_html_of` maps a
/// run to its replay page when it has one.
[[nodiscard]] nlohmann::json bench_report_object(const std::filesystem::path& bench_out,
                                                 const std::filesystem::path& html_dir);

/// Writes the bench report page of `bench_out` to `html`, and beside each recorded replay
/// (bench_out/replays/*.otr) its self-contained page. Returns the replay pages written.
std::vector<std::filesystem::path> write_bench_report(const std::filesystem::path& bench_out,
                                                      const std::filesystem::path& html,
                                                      std::string_view report_template,
                                                      std::string_view viewer_template);

/// The file name of a bench run's replay: <policy>-<traffic>-seed<N>.otr.
[[nodiscard]] std::string bench_replay_name(const std::string& policy, const std::string& traffic,
                                            std::uint64_t seed);

/// Options of `overtake view`.
struct ViewOptions {
  std::filesystem::path replay;
  std::string host = "127.0.0.1";
  int port = 8080;
  std::optional<std::filesystem::path> html;  ///< write a self-contained page and exit
  bool partial = false;                       ///< accept a cut-short replay
  bool quiet = false;
};

/// `overtake view`: checks the replay, then writes the page (--html) or serves it until
/// `stop` is set. `on_listening` gets the page's address (it is also printed unless quiet).
/// Throws UsageError for bad flags and std::runtime_error for a bad replay or a port in use.
int run_view(const ViewOptions& opts, const std::atomic<bool>& stop,
             const std::function<void(const std::string& url)>& on_listening = {});

}  // namespace overtake::app
