#pragma once
// Base64 (RFC 4648): replays embedded in pages, blobs in scenario files.

#include <optional>
#include <string>
#include <string_view>

namespace overtake::core {

/// Standard base64 (RFC 4648, with padding, no line breaks).
[[nodiscard]] std::string base64_encode(std::string_view bytes);
/// Decodes standard base64 (whitespace ignored); nullopt when it is not valid base64.
[[nodiscard]] std::optional<std::string> base64_decode(std::string_view text);

}  // namespace overtake::core
