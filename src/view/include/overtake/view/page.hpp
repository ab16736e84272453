#pragma once
// The pages' data: the viewer page (web/dist/viewer.html) and the bench report page
// (web/dist/report.html) carry placeholders inside <script> elements; these functions put
// the data in (docs/replay.md, "The page's data placeholders"). Pure string work.

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace overtake::view {

/// A page or server problem the user must hear about (a page without its placeholder, a port
/// in use, ...); the message says what and where.
class ViewError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Where the viewer page takes its replay from.
enum class ViewerSource {
  embedded,  ///< base64 in the page's data element (a self-contained file)
  http,      ///< GET /replay.otr from the server that served the page
  live,      ///< the websocket /live of a run in progress
};

inline constexpr std::string_view kConfigElementId = "overtake-config";
inline constexpr std::string_view kConfigPlaceholder = "__OVERTAKE_CONFIG__";
inline constexpr std::string_view kDataElementId = "overtake-data";
inline constexpr std::string_view kDataPlaceholder = "__OVERTAKE_DATA__";
inline constexpr std::string_view kBenchElementId = "overtake-bench";
inline constexpr std::string_view kBenchPlaceholder = "__OVERTAKE_BENCH__";
inline constexpr std::string_view kReplayUrlPath = "/replay.otr";
inline constexpr std::string_view kLiveUrlPath = "/live";

/// JSON text made safe inside a <script> element: every '<' becomes \u003c (valid JSON, and
/// no "</script>" can end the element early).
[[nodiscard]] std::string script_safe_json(std::string_view json_text);

/// `page` with the text content of the <script> element whose id is `id` replaced by
/// `content`. Throws ViewError when the page has no such element or the element does not
/// hold `placeholder` (a page that was filled already, or the wrong page).
[[nodiscard]] std::string fill_script_element(std::string_view page, std::string_view id,
                                              std::string_view placeholder,
                                              std::string_view content);

/// The viewer's config object for a source (see ViewerSource), as JSON text; `name` (when
/// given) is the replay's file name, which the page shows in its "cut a scenario here"
/// command (only the name: a shared page does not tell the folders it came from).
[[nodiscard]] std::string viewer_config_json(ViewerSource source, std::string_view name = {});

/// The viewer page filled: its config for `source` (and `name`), and for
/// ViewerSource::embedded the base64 of `replay_bytes` (the data element is left empty
/// otherwise).
[[nodiscard]] std::string viewer_page(std::string_view page_template, ViewerSource source,
                                      std::string_view replay_bytes = {},
                                      std::string_view name = {});

/// The bench report page filled with the bench object (JSON text, made script-safe here).
[[nodiscard]] std::string report_page(std::string_view page_template, std::string_view bench_json);

}  // namespace overtake::view
