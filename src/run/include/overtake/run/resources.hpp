#pragma once
// Files built into the binary: the shipped config, the default track, and the web pages
// "viewer.html" and "report.html" (built from web/; placeholders in docs/replay.md).

#include <optional>
#include <string_view>

namespace overtake::resources {

/// The bytes of an embedded file, or nullopt when there is none of that name.
[[nodiscard]] std::optional<std::string_view> embedded_file(std::string_view name);

}  // namespace overtake::resources
