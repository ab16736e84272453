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

#include "overtake/replay/replay.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/view/server.hpp"

namespace overtake::run {

inline constexpr std::string_view kViewerPageName = "viewer.html";
inline constexpr std::string_view kReportPageName = "report.html";

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

}  // namespace overtake::run
