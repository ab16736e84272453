#pragma once
// The bench report page (`bench --html`): bench.json, the runs and the summary as one page,
// with a page beside each recorded replay.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace overtake::batch {

/// Folder of a bench's recorded replays, inside its --out folder.
inline constexpr std::string_view kReplaysFolder = "replays";

/// The bench report's data (docs/replay.md): bench.json's object with "runs" (each with
/// "replay": a link relative to `html_dir`, or null) and "summary". `replay_html_of` maps a
/// run to its replay page when it has one.
/// `risk_dirs`: `overtake risk` folders of at-fault estimates, drawn on the speed-against-
/// safety chart beside the rows (the object's "risk", batch::risk_chart_point's each).
[[nodiscard]] nlohmann::json bench_report_object(
    const std::filesystem::path& bench_out, const std::filesystem::path& html_dir,
    const std::vector<std::filesystem::path>& risk_dirs = {});

/// Writes the bench report page of `bench_out` to `html`, and beside each recorded replay
/// (bench_out/replays/*.otr) its self-contained page. Returns the replay pages written.
std::vector<std::filesystem::path> write_bench_report(
    const std::filesystem::path& bench_out, const std::filesystem::path& html,
    std::string_view report_template, std::string_view viewer_template,
    const std::vector<std::filesystem::path>& risk_dirs = {});

/// write_bench_report with the pages embedded in the binary, saying on stdout (unless `quiet`)
/// where the page is and how many replay pages it links.
void write_bench_report_page(const std::filesystem::path& bench_out,
                             const std::filesystem::path& html, bool quiet,
                             const std::vector<std::filesystem::path>& risk_dirs = {});

/// Throws std::runtime_error when a page the report needs is not in the binary: checked
/// before any run, so that none is run in vain.
void check_report_pages();

/// The files a bench writes, as a command line names them: {runs.jsonl,summary.md,...}.
[[nodiscard]] std::string bench_files_text();

/// The file name of a bench run's replay: <policy>-<traffic>-seed<N>.otr.
[[nodiscard]] std::string bench_replay_name(const std::string& policy, const std::string& traffic,
                                            std::uint64_t seed);

}  // namespace overtake::batch
