// `overtake tune`: the validation on held-out seeds (the start against the best, paired, on
// each map; with a risk, their estimates on runs of their own) and the summary.

#include <cmath>
#include <iostream>

#include "overtake/base/errors.hpp"
#include "overtake/base/text.hpp"
#include "overtake/eval/compare.hpp"
#include "overtake/eval/metrics.hpp"
#include "tune_internal.hpp"

namespace overtake::batch::tune_detail {

using base::fixed_text;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// The validation of one map: the start and the best benched on the held-out seeds into
// `dir`/start and `dir`/best, compared (null when interrupted).
json validate_on(const TuneSpec& spec, const Target& target, const std::vector<double>& start,
                 const std::vector<double>& best, const MapChoice& map, const fs::path& dir,
                 const std::atomic<bool>* stop, bool& interrupted) {
  for (const auto& [name, x] : {std::pair{"start", start}, std::pair{"best", best}}) {
    const BenchSpec b = bench_of(spec, target, x, spec.validation_seeds, map, dir / name,
                                 dir / (std::string(name) + "-config.json"));
    if (run_bench_of(spec, b, stop, nullptr)) {
      interrupted = true;
      return nullptr;
    }
  }
  return compare_bench_folders(dir / "start", dir / "best", {});
}

// Whether the training gain holds on the held-out seeds, from the validation's verdict on the
// objective (a metric of the evaluation; a count is judged by its rate per 100 miles).
std::string verdict_of(const TuneSpec& spec, const json& validation);

}  // namespace

// The validation on every map, in validation/ (validation/map-K/ for several maps).
std::vector<TuneValidation> run_validation(const TuneSpec& spec, const Target& target,
                                           const std::vector<double>& start,
                                           const std::vector<double>& best,
                                           const std::atomic<bool>* stop, bool& interrupted) {
  const fs::path dir = spec.out / kTuneValidationFolder;
  std::error_code ignored;
  if (!spec.run_bench_elsewhere) fs::remove_all(dir, ignored);
  const std::vector<MapChoice> maps = maps_of(spec);
  std::vector<TuneValidation> out;
  for (std::size_t k = 0; k < maps.size(); ++k) {
    json c = validate_on(spec, target, start, best, maps[k], map_folder(dir, k, maps.size()), stop,
                         interrupted);
    if (interrupted) return {};
    std::string verdict = verdict_of(spec, c);
    TuneValidation v{map_label(maps[k]), std::move(c), std::move(verdict), nullptr, ""};
    if (spec.risk) {
      const fs::path at = map_folder(dir, k, maps.size());
      v.risk = tune_detail::validate_risk_on(
          spec, risk_planner(spec, target, start, at / "start-config.json"),
          risk_planner(spec, target, best, at / "best-config.json"), maps[k], at, stop,
          interrupted);
      if (interrupted) return {};
      v.risk_verdict = tune_detail::risk_verdict_of(spec, v.risk);
    }
    out.push_back(std::move(v));
  }
  return out;
}

namespace {

std::string verdict_of(const TuneSpec& spec, const json& validation) {
  std::string metric = spec.objective;
  if (!eval::parse_metric(metric)) metric += "_per_100mi";
  if (!eval::parse_metric(metric) || validation["comparisons"].empty()) {
    return "The validation has no verdict on " + spec.objective + ".";
  }
  const json& f = validation["comparisons"][0]["figures"][metric];
  if (f.is_null()) return "The validation has no verdict on " + metric + ".";
  const std::string verdict = f["verdict"].get<std::string>();
  std::string change = "change " + fixed_text(f["difference"].get<double>(), 3);
  if (f["ci"].is_array()) {
    change += " (95% interval " + fixed_text(f["ci"][0].get<double>(), 3) + " to " +
              fixed_text(f["ci"][1].get<double>(), 3) + ")";
  }
  const std::string seeds = std::to_string(spec.validation_seeds.size()) + " held-out seeds";
  if (verdict == "better") {
    return "The gain holds on the held-out seeds: " + metric + " better on " + seeds + ", " +
           change + ".";
  }
  if (verdict == "worse") {
    return "The gain does NOT hold: on " + seeds + " the best is worse than the start in " +
           metric + ", " + change + " (it fits its training seeds only).";
  }
  return "Not shown to hold: on " + seeds +
         " the best is not different from the start beyond "
         "noise in " +
         metric + " (" + verdict + "), " + change + ".";
}

// A trial's risk as the summary shows it: "0.123 (0.01-0.5)", or why there is none.
std::string risk_cell(const TuneTrial& t) {
  const json& f = t.figures;
  if (!f.value("risk_per_100mi", json()).is_number()) return "-";
  return fixed_text(f["risk_per_100mi"].get<double>(), 3) + " (" +
         fixed_text(f["risk_low_per_100mi"].get<double>(), 3) + "-" +
         fixed_text(f["risk_high_per_100mi"].get<double>(), 3) + ")";
}

}  // namespace

std::string summary_of(const TuneSpec& spec, const TuneOutcome& o) {
  std::string s = "# overtake tune: " + spec.policy + "\n\n";
  s +=
      "Objective: " + spec.objective +
      (tune_figure_higher_is_better(spec.objective) ? " (higher is better)" : " (lower is better)");
  std::string cs;
  for (const auto& c : constraints_of(spec)) {
    cs += (cs.empty() ? "" : ", ") + c.figure + (c.at_most ? " <= " : " >= ") +
          base::shortest_text(c.bound);
  }
  s += "; constraints: " + (cs.empty() ? std::string("none") : cs) + ".\n";
  s += "Training: " + std::to_string(spec.seeds.size()) + " seeds x " +
       base::shortest_text(spec.minutes) + " min per traffic profile" +
       (spec.maps.size() > 1 ? " on each of " + std::to_string(spec.maps.size()) + " maps" : "") +
       "; " + std::to_string(o.trials.size()) + " trials (" + spec.algorithm + "); ended by " +
       o.stop_reason + ".\n";
  if (spec.risk) {
    s += "Risk: each trial's " + spec.risk->event.name() + " rate per 100 mi by `overtake risk`, " +
         base::shortest_text(spec.risk->hours) +
         " simulated hours per map and traffic profile, on the same runs for every trial "
         "(seeds from " +
         std::to_string(spec.risk->first_seed) + ").\n";
  }
  s += "\n| trial |";
  for (const auto& p : spec.params) s += " " + p.name + " |";
  s += " " + spec.objective + " |" + (spec.risk ? " risk_per_100mi (95% interval) |" : "") +
       " feasible |\n|---:|";
  for (std::size_t i = 0; i < spec.params.size(); ++i) s += "---:|";
  s += std::string(spec.risk ? "---:|" : "") + "---:|---|\n";
  const auto row = [&](const TuneTrial& t, const std::string& label) {
    s += "| " + label + " |";
    for (const auto& p : spec.params) s += " " + base::shortest_text(t.params.at(p.name)) + " |";
    s += " " + (std::isfinite(t.objective) ? fixed_text(t.objective, 3) : std::string("-")) + " |";
    if (spec.risk) s += " " + risk_cell(t) + " |";
    s += " " + (t.feasible ? std::string("yes") : "no: " + t.violations.front()) + " |\n";
  };
  if (!o.trials.empty()) row(o.trials.front(), "1 (start)");
  if (o.best && *o.best != 1) {
    row(o.trials[static_cast<std::size_t>(*o.best - 1)], std::to_string(*o.best) + " (best)");
  }
  if (!o.best) s += "\nNo trial met the constraints.\n";
  if (!o.validations.empty()) s += "\n## Validation on held-out seeds\n";
  for (const TuneValidation& v : o.validations) {
    if (o.validations.size() > 1) s += "\n### On " + v.map + "\n";
    s += "\n" + v.verdict + "\n\n```\n" + eval::compare_text(v.comparison) + "```\n";
    if (!v.risk_verdict.empty()) s += "\n" + v.risk_verdict + "\n";
  }
  if (o.validations.empty() && o.best && spec.validation_seeds.empty()) {
    s += "\nNo validation (no --validate-seeds).\n";
  }
  if (o.interrupted) s += "\nInterrupted: the trials above are those that finished.\n";
  return s;
}

}  // namespace overtake::batch::tune_detail

namespace overtake::batch {

int report_tune(const TuneSpec& spec, const TuneOutcome& o, bool quiet) {
  if (!quiet) {
    std::cout << o.summary_markdown;
    if (!o.best_command.empty()) std::cout << "\nbest command: " << o.best_command << "\n";
    std::cout << "\nwrote " << (spec.out / kTuneTrialsFile).string() << ", "
              << (spec.out / kTuneSummaryFile).string() << ", "
              << (spec.out / kTunePageFile).string();
    if (o.best) std::cout << ", " << (spec.out / kTuneBestFile).string();
    std::cout << "\n";
  }
  if (o.interrupted) {
    std::cerr << "overtake tune: interrupted; " << o.trials.size()
              << " finished trials kept (--resume goes on)\n";
    return base::kExitInterrupted;
  }
  if (!o.best) {
    std::cerr << "overtake tune: no trial met the constraints\n";
    return base::kExitFailure;
  }
  return base::kExitOk;
}

}  // namespace overtake::batch
