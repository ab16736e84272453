#pragma once
// Checks on text that comes from outside before a library is given it, and text made safe
// before it is written: how deep a JSON text nests (a parser and a printer recurse once per
// level, so 100,000 levels overflow the stack), and UTF-8 (which JSON output requires).

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace overtake::core {

/// How deep arrays and objects may nest in any JSON overtake reads. Its own files nest at
/// most 6 deep (a scenario's expectations); 64 leaves room and keeps a recursion shallow.
inline constexpr int kMaxJsonDepth = 64;

/// The byte offset of the first `[` or `{` that opens level max_depth + 1, if any (brackets
/// inside strings do not count). One pass, no recursion; the text need not be valid JSON.
[[nodiscard]] std::optional<std::size_t> json_too_deep_at(std::string_view text,
                                                          int max_depth = kMaxJsonDepth);

/// Throws std::invalid_argument "SOURCE: JSON nested deeper than 64 levels (at byte N)" when
/// the text nests deeper than max_depth.
void require_json_depth(std::string_view text, std::string_view source,
                        int max_depth = kMaxJsonDepth);

/// Whether text is well-formed UTF-8 (no overlong forms, no surrogates, nothing past U+10FFFF).
[[nodiscard]] bool is_valid_utf8(std::string_view text);

/// The text with each byte that does not belong to a well-formed UTF-8 sequence replaced by
/// U+FFFD (the replacement character); valid text comes back unchanged.
[[nodiscard]] std::string valid_utf8(std::string_view text);

}  // namespace overtake::core
