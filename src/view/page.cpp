#include "overtake/view/page.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>

namespace overtake::view {
namespace {

constexpr std::string_view kAlphabet =
    "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
constexpr std::string_view kScriptClose = "</script";

constexpr std::array<int, 256> decode_table() {
  std::array<int, 256> t{};
  for (int& v : t) v = -1;
  for (std::size_t i = 0; i < kAlphabet.size(); ++i) {
    t[static_cast<unsigned char>(kAlphabet[i])] = static_cast<int>(i);
  }
  return t;
}

bool is_space(char c) {
  return c == ' ' || c == '\n' || c == '\r' || c == '\t';
}

std::string_view trimmed(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

}  // namespace

std::string base64_encode(std::string_view bytes) {
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  const auto at = [&](std::size_t k) {
    return static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[k]));
  };
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t v = (at(i) << 16) | (at(i + 1) << 8) | at(i + 2);
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back(kAlphabet[(v >> 6) & 63]);
    out.push_back(kAlphabet[v & 63]);
  }
  const std::size_t rest = bytes.size() - i;
  if (rest == 1) {
    const std::uint32_t v = at(i) << 16;
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out += "==";
  } else if (rest == 2) {
    const std::uint32_t v = (at(i) << 16) | (at(i + 1) << 8);
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back(kAlphabet[(v >> 6) & 63]);
    out.push_back('=');
  }
  return out;
}

std::optional<std::string> base64_decode(std::string_view text) {
  static constexpr std::array<int, 256> kTable = decode_table();
  std::string out;
  out.reserve(text.size() / 4 * 3);
  std::uint32_t acc = 0;
  int bits = 0;
  int pad = 0;
  std::size_t symbols = 0;
  for (const char c : text) {
    if (is_space(c)) continue;
    ++symbols;
    if (c == '=') {
      ++pad;
      continue;
    }
    if (pad > 0) return std::nullopt;  // data after padding
    const int v = kTable[static_cast<unsigned char>(c)];
    if (v < 0) return std::nullopt;
    acc = (acc << 6) | static_cast<std::uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<char>((acc >> bits) & 0xff));
    }
  }
  if (symbols % 4 != 0 || pad > 2) return std::nullopt;
  return out;
}

std::string script_safe_json(std::string_view json_text) {
  std::string out;
  out.reserve(json_text.size());
  for (const char c : json_text) {
    if (c == '<') {
      out += "\\u003c";
    } else {
      out.push_back(c);
    }
  }
  return out;
}

std::string fill_script_element(std::string_view page, std::string_view id,
                                std::string_view placeholder, std::string_view content) {
  // The first `id="..."` (or 'id=...') that sits inside a <script ...> opening tag; the
  // page's code may mention the same text elsewhere.
  std::size_t open_end = std::string_view::npos;
  for (const std::string& attr_text :
       {"id=\"" + std::string(id) + "\"", "id='" + std::string(id) + "'"}) {
    for (std::size_t attr = page.find(attr_text); attr != std::string_view::npos;
         attr = page.find(attr_text, attr + 1)) {
      const std::size_t open = page.rfind("<script", attr);
      if (open == std::string_view::npos) continue;
      if (page.substr(open, attr - open).find('>') != std::string_view::npos) continue;
      open_end = page.find('>', attr);
      break;
    }
    if (open_end != std::string_view::npos) break;
  }
  if (open_end == std::string_view::npos) {
    throw ViewError("the page has no <script id=\"" + std::string(id) + "\"> element");
  }
  const std::size_t body = open_end + 1;
  const std::size_t close = page.find(kScriptClose, body);
  if (close == std::string_view::npos) {
    throw ViewError("the page's <script id=\"" + std::string(id) + "\"> element is not closed");
  }
  if (trimmed(page.substr(body, close - body)) != placeholder) {
    throw ViewError("the page's <script id=\"" + std::string(id) + "\"> element does not hold " +
                    std::string(placeholder) + " (was it filled already?)");
  }
  std::string out;
  out.reserve(page.size() - (close - body) + content.size());
  out.append(page.substr(0, body));
  out.append(content);
  out.append(page.substr(close));
  return out;
}

std::string viewer_config_json(ViewerSource source, std::string_view name) {
  nlohmann::json j;
  switch (source) {
    case ViewerSource::embedded:
      j = {{"source", "embedded"}};
      break;
    case ViewerSource::http:
      j = {{"source", "http"}, {"url", kReplayUrlPath}};
      break;
    case ViewerSource::live:
      j = {{"source", "live"}, {"url", kLiveUrlPath}};
      break;
  }
  if (!name.empty()) j["name"] = std::string(name);
  return j.dump();
}

std::string viewer_page(std::string_view page_template, ViewerSource source,
                        std::string_view replay_bytes, std::string_view name) {
  std::string page = fill_script_element(page_template, kConfigElementId, kConfigPlaceholder,
                                         script_safe_json(viewer_config_json(source, name)));
  const std::string data = source == ViewerSource::embedded ? base64_encode(replay_bytes) : "";
  return fill_script_element(page, kDataElementId, kDataPlaceholder, data);
}

std::string report_page(std::string_view page_template, std::string_view bench_json) {
  return fill_script_element(page_template, kBenchElementId, kBenchPlaceholder,
                             script_safe_json(bench_json));
}

}  // namespace overtake::view
