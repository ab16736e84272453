#pragma once
// Small text helpers every room uses: numbers as tables print them, words quoted for sh, and
// the comma-separated lists of names that flags take, JSON as text.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace overtake::base {

/// JSON as text (indented by `indent` spaces, or on one line when -1) that is always valid
/// UTF-8: a byte of a string that is not (a Latin-1 file name, a planner's reason cut in the
/// middle of a character) is written as U+FFFD instead of stopping the output.
template <class Json>
[[nodiscard]] std::string json_text(const Json& j, int indent = -1) {
  return j.dump(indent, ' ', false, Json::error_handler_t::replace);
}

/// `value` with `digits` decimals (for messages and tables).
[[nodiscard]] std::string fixed_text(double value, int digits);

/// `text` quoted for sh: as it is when only safe characters, else in single quotes.
[[nodiscard]] std::string shell_quote(std::string_view text);

/// A comma-separated list of names (policies, traffic profiles); spaces and empty items
/// are dropped.
[[nodiscard]] std::vector<std::string> split_list(const std::string& text);

/// `items` joined with `separator` ("a, b", or "a,b" for a flag that split_list reads back).
[[nodiscard]] std::string join_list(const std::vector<std::string>& items,
                                    std::string_view separator);

/// The shortest text that reads back as the same double (a value put into a flag, a
/// command or a message).
[[nodiscard]] std::string shortest_text(double value);

/// Throws UsageError naming `flag` and the name when `names` holds one twice: a list flag
/// (--policies, --traffic, --maps) names each thing once, or its runs would be driven, and
/// their failures counted, twice.
void check_unique_names(const std::vector<std::string>& names, const std::string& flag);

/// The number of single-character edits (insertions, deletions, substitutions, swaps of two
/// neighbours) that turn `a` into `b`.
[[nodiscard]] std::size_t edit_distance(std::string_view a, std::string_view b);

/// The word of `words` nearest to `typed` by edit_distance, when near enough to be a mistyping
/// of it (at most 2 edits, or a third of the typed length), else none.
[[nodiscard]] std::optional<std::string> nearest_word(const std::vector<std::string>& words,
                                                      std::string_view typed);

}  // namespace overtake::base
