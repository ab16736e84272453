// Text from outside that overtake checks before a library reads it, or writes into JSON: a
// plugin's failure reason, a file name, any JSON text. Each property failing is a finding:
// - core::valid_utf8 gives valid UTF-8 and gives valid text back unchanged; the text as JSON
//   (as base::json_text writes it, stray bytes as U+FFFD) parses back to valid UTF-8, the same
//   text when it was valid;
// - core::json_too_deep_at finds a `[` or `{` when it finds anything; when it finds nothing, a
//   text that parses is a value no deeper than core::kMaxJsonDepth, and it writes and reads
//   back as the same value.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "overtake/core/text_check.hpp"

namespace {

using nlohmann::json;
namespace core = overtake::core;

int depth_of(const json& j) {
  int deepest = 0;
  if (j.is_array() || j.is_object()) {
    for (const json& v : j) deepest = std::max(deepest, depth_of(v));
    return deepest + 1;
  }
  return 0;
}

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);

  const std::string fixed = core::valid_utf8(text);
  check(core::is_valid_utf8(fixed));
  if (core::is_valid_utf8(text)) check(fixed == text);
  const std::string written =
      json(std::string(text)).dump(-1, ' ', false, json::error_handler_t::replace);
  const std::string read_back = json::parse(written).get<std::string>();
  check(core::is_valid_utf8(read_back));
  if (core::is_valid_utf8(text)) check(read_back == text);

  if (const auto at = core::json_too_deep_at(text)) {
    check(*at < text.size() && (text[*at] == '[' || text[*at] == '{'));
    return 0;
  }
  const json j = json::parse(text, nullptr, false);
  if (j.is_discarded()) return 0;
  check(depth_of(j) <= core::kMaxJsonDepth);
  check(json::parse(j.dump()) == j);
  return 0;
}
