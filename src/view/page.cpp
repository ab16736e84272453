#include "overtake/view/page.hpp"

#include <nlohmann/json.hpp>

#include "overtake/core/base64.hpp"

namespace overtake::view {
namespace {

constexpr std::string_view kScriptClose = "</script";

bool is_space(char c) {
  return c == ' ' || c == '\n' || c == '\r' || c == '\t';
}

std::string_view trimmed(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

}  // namespace

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
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);  // stray bytes: U+FFFD
}

std::string viewer_page(std::string_view page_template, ViewerSource source,
                        std::string_view replay_bytes, std::string_view name) {
  std::string page = fill_script_element(page_template, kConfigElementId, kConfigPlaceholder,
                                         script_safe_json(viewer_config_json(source, name)));
  const std::string data =
      source == ViewerSource::embedded ? core::base64_encode(replay_bytes) : "";
  return fill_script_element(page, kDataElementId, kDataPlaceholder, data);
}

std::string report_page(std::string_view page_template, std::string_view bench_json) {
  return fill_script_element(page_template, kBenchElementId, kBenchPlaceholder,
                             script_safe_json(bench_json));
}

}  // namespace overtake::view
