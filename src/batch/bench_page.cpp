#include "overtake/batch/bench_page.hpp"
#include "overtake/base/text.hpp"

#include <cstdio>
#include <iostream>
#include <set>

#include "overtake/base/io.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/eval/summary.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/pages.hpp"
#include "overtake/view/page.hpp"

namespace overtake::batch {

using base::json_text;
using base::write_file_atomic;
using run::load_replay_for_view;
using run::read_json_file;
using run::write_viewer_html;
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

// `to` relative to the folder `from_dir`, with forward slashes (a link in a page).
std::string link_between(const fs::path& from_dir, const fs::path& to) {
  const fs::path rel = fs::absolute(to).lexically_normal().lexically_relative(
      fs::absolute(from_dir).lexically_normal());
  return rel.generic_string();
}

}  // namespace

std::string bench_replay_name(const std::string& policy, const std::string& traffic,
                              std::uint64_t seed) {
  return policy + "-" + traffic + "-seed" + std::to_string(seed) + ".otr";
}

json bench_report_object(const fs::path& bench_out, const fs::path& html_dir,
                         const std::vector<fs::path>& risk_dirs) {
  json out;
  out = read_json_file(bench_out / kBenchManifestFile);
  const std::vector<json> runs = load_bench_runs(bench_out);
  json with_links = json::array();
  for (json r : runs) {
    const fs::path otr = bench_out / kReplaysFolder /
                         bench_replay_name(r["config"]["policy"].get<std::string>(),
                                           r["config"]["traffic"].get<std::string>(),
                                           r["config"]["seed"].get<std::uint64_t>());
    fs::path page = otr;
    page.replace_extension(".html");
    r["replay"] = fs::exists(page) ? json(link_between(html_dir, page)) : json(nullptr);
    with_links.push_back(std::move(r));
  }
  out["runs"] = std::move(with_links);
  BenchSummary summary = summarize_bench(runs, out.at("policies").get<std::vector<std::string>>(),
                                         out.at("traffic").get<std::vector<std::string>>(),
                                         (bench_out / kBenchRunsFile).string());
  out["summary"] = std::move(summary.rows);
  out["verdicts"] = eval::verdict_method(eval::family_size(summary.pairs));
  out["pairs"] = std::move(summary.pairs);
  json risk = json::array();
  for (const fs::path& dir : risk_dirs) risk.push_back(risk_chart_point(dir));
  out["risk"] = std::move(risk);
  return out;
}

std::vector<fs::path> write_bench_report(const fs::path& bench_out, const fs::path& html,
                                         std::string_view report_template,
                                         std::string_view viewer_template,
                                         const std::vector<fs::path>& risk_dirs) {
  std::vector<fs::path> pages;
  const fs::path replays = bench_out / kReplaysFolder;
  std::error_code ec;
  if (fs::is_directory(replays, ec)) {
    std::set<fs::path> otrs;
    for (const auto& entry : fs::directory_iterator(replays)) {
      if (entry.path().extension() == ".otr") otrs.insert(entry.path());
    }
    for (const fs::path& otr : otrs) {
      fs::path page = otr;
      page.replace_extension(".html");
      std::string warning;
      std::string bytes;
      try {
        bytes = load_replay_for_view(otr, true, &warning);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "bench: %s: not linked from the report: %s\n", otr.c_str(), e.what());
        fs::remove(page, ec);
        continue;
      }
      if (!warning.empty()) std::fprintf(stderr, "bench: warning: %s\n", warning.c_str());
      write_viewer_html(bytes, page, viewer_template, otr.filename().string());
      pages.push_back(page);
    }
  }
  fs::path dir = html.parent_path();
  if (dir.empty()) dir = ".";
  const json object = bench_report_object(bench_out, dir, risk_dirs);
  write_file_atomic(html, view::report_page(report_template, json_text(object)));
  return pages;
}

void write_bench_report_page(const fs::path& bench_out, const fs::path& html, bool quiet,
                             const std::vector<fs::path>& risk_dirs) {
  const auto pages = write_bench_report(bench_out, html, run::embedded_page(run::kReportPageName),
                                        run::embedded_page(run::kViewerPageName), risk_dirs);
  if (!quiet) {
    std::cout << "report: " << html.string() << " (" << pages.size() << " replay page"
              << (pages.size() == 1 ? "" : "s") << " linked)\n";
  }
}

void check_report_pages() {
  (void)run::embedded_page(run::kReportPageName);
  (void)run::embedded_page(run::kViewerPageName);
}

std::string bench_files_text() {
  std::string text = "{";
  for (const char* name : kBenchFiles) {
    text += std::string(text.size() > 1 ? "," : "") + name;
  }
  return text + "}";
}

}  // namespace overtake::batch
