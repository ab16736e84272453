#pragma once
// Files built into the binary (the shipped config and the default track).

#include <optional>
#include <string_view>

namespace overtake::resources {

/// The bytes of an embedded file, or nullopt when there is none of that name.
[[nodiscard]] std::optional<std::string_view> embedded_file(std::string_view name);

}  // namespace overtake::resources
