// `overtake compare` of two `overtake risk` folders: the ratio of their rates with its
// interval and a verdict (eval::rate_ratio), and what makes them of different roads.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

#include "overtake/base/text.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/eval/splitting.hpp"
#include "overtake/eval/stats.hpp"
#include "overtake/eval/summary.hpp"
#include "overtake/run/config.hpp"

namespace overtake::batch {

using nlohmann::json;

namespace {
constexpr double kMetresPerMile = 1609.344;
}  // namespace

bool holds_risk(const std::filesystem::path& dir) {
  return std::filesystem::is_regular_file(dir / "risk.json");
}

namespace {

struct RiskFile {
  json j;
  eval::RateEstimate rate;
};

RiskFile read_risk_file(const std::filesystem::path& dir) {
  const auto file = dir / "risk.json";
  RiskFile f;
  f.j = run::read_json_file(file);
  const auto bad = [&](const std::string& why) {
    throw std::runtime_error(file.string() + ": " + why);
  };
  const auto number = [&](const char* key) {
    if (!f.j.contains(key) || !f.j[key].is_number()) bad(std::string(key) + " is not a number");
    const double x = f.j[key].get<double>();
    if (!std::isfinite(x) || x < 0.0) bad(std::string(key) + " is negative or not finite");
    return x;
  };
  if (!f.j.is_object() || !f.j.contains("event") || !f.j["event"].is_string())
    bad("not a risk estimate (no event)");
  f.rate.rate = number("rate_per_100mi");
  const json& ci = f.j.value("ci95_per_100mi", json());
  if (!ci.is_array() || ci.size() != 2 || !ci[0].is_number() || !ci[1].is_number())
    bad("ci95_per_100mi is not [low, high]");
  f.rate.ci = {ci[0].get<double>(), ci[1].get<double>()};
  if (!(f.rate.ci.lo >= 0.0 && f.rate.ci.lo <= f.rate.ci.hi && std::isfinite(f.rate.ci.hi)))
    bad("ci95_per_100mi is not an interval of rates");
  f.rate.upper_bound_only = f.j.value("upper_bound_only", false);
  return f;
}

// Each base run's miles and hours by seed, from the folder's runs.jsonl (empty when there is
// none: an estimate written before it, or by hand).
std::map<std::uint64_t, std::pair<double, double>> runs_by_seed(const std::filesystem::path& dir) {
  std::map<std::uint64_t, std::pair<double, double>> out;
  std::ifstream in(dir / "runs.jsonl");
  for (std::string line; std::getline(in, line);) {
    try {
      const json r = json::parse(line);
      const double metres = r.at("exposure_m").get<double>();
      const double seconds = r.at("base_cost_s").get<double>();
      if (std::isfinite(metres) && std::isfinite(seconds) && metres >= 0.0 && seconds > 0.0)
        out[r.at("seed").get<std::uint64_t>()] = {metres / kMetresPerMile, seconds / 3600.0};
    } catch (const std::exception&) {
      // A line cut short (the last, by a crash) is skipped, as --resume skips it.
    }
  }
  return out;
}

// The two planners' mean speeds on the seeds both estimates drove (on the same map, traffic
// and run length: their runs are the same runs of the world), paired by seed: the bench's
// bootstrap-t interval of the difference and its paired t-test. Null (with a note) when they
// share fewer than eval::kMinSeeds seeds or drove different roads.
json speed_on_common_seeds(const std::filesystem::path& base,
                           const std::filesystem::path& candidate, bool same_roads, json& notes) {
  const auto a = runs_by_seed(base);
  const auto b = runs_by_seed(candidate);
  std::vector<double> ma, ha, mb, hb;
  for (const auto& [seed, run] : a) {
    const auto it = b.find(seed);
    if (it == b.end()) continue;
    ma.push_back(run.first);
    ha.push_back(run.second);
    mb.push_back(it->second.first);
    hb.push_back(it->second.second);
  }
  if (!same_roads) return nullptr;
  if (ma.size() < eval::kMinSeeds) {
    notes.push_back("the estimates share " + std::to_string(ma.size()) +
                    " seeds: too few to compare their speeds (at least " +
                    std::to_string(eval::kMinSeeds) + "; give them the same --first-seed)");
    return nullptr;
  }
  const auto sum = [](const std::vector<double>& v) {
    double t = 0.0;
    for (double x : v) t += x;
    return t;
  };
  const double speed_a = sum(ma) / sum(ha);
  const double speed_b = sum(mb) / sum(hb);
  const eval::PairedRatios pairs{mb, hb, ma, ha};  // candidate - base
  eval::BootstrapOptions boot;
  boot.seed = eval::bootstrap_seed("risk-speed|" + std::to_string(ma.size()));
  const eval::Interval ci = eval::mean_difference_interval(pairs, boot);
  const double p = eval::mean_difference_p_value(pairs);
  const std::string verdict = ci.lo > 0.0 ? "faster" : (ci.hi < 0.0 ? "slower" : "no difference");
  return {{"seeds", ma.size()},
          {"base_mph", speed_a},
          {"candidate_mph", speed_b},
          {"difference_mph", speed_b - speed_a},
          {"ci95_mph", {ci.lo, ci.hi}},
          {"p_value", p},
          {"verdict", verdict},
          {"method",
           "paired by seed: the bootstrap-t interval of the difference of miles over hours "
           "(the bench's), on the seeds both drove"}};
}

}  // namespace

json compare_risk_folders(const std::filesystem::path& base,
                          const std::filesystem::path& candidate) {
  const RiskFile a = read_risk_file(base);
  const RiskFile b = read_risk_file(candidate);
  if (a.j["event"] != b.j["event"]) {
    throw std::runtime_error("the estimates count different events (" + a.j["event"].dump() +
                             " in " + base.string() + ", " + b.j["event"].dump() + " in " +
                             candidate.string() + "): their rates do not compare");
  }
  json notes = json::array();
  for (const char* key : {"map", "traffic", "minutes_per_run"}) {
    if (a.j.value(key, json()) != b.j.value(key, json())) {
      notes.push_back(std::string(key) + " differs (" + a.j.value(key, json()).dump() + ", " +
                      b.j.value(key, json()).dump() + "): the rates are of different roads");
    }
  }
  const bool same_roads = notes.empty();
  // Runs cut short by the planner's failure: the rate is one of the miles it could drive.
  for (const auto& [f, dir] : {std::pair{&a, &base}, std::pair{&b, &candidate}}) {
    const long ended = f->j.value("runs_ended_by_planner", 0L);
    if (ended > 0) {
      notes.push_back(dir->string() + ": " + std::to_string(ended) + " of " +
                      std::to_string(f->j.value("runs", 0L)) +
                      " runs ended by the planner's failure (their miles until then counted)");
    }
  }
  const json speed = speed_on_common_seeds(base, candidate, same_roads, notes);
  const eval::RateRatio r = eval::rate_ratio(a.rate, b.rate);
  const auto side = [](const RiskFile& f, const std::filesystem::path& dir) {
    std::string who = f.j.value("policy", "");
    if (!f.j.value("config", "").empty()) who += " with " + f.j.value("config", "");
    return json{{"folder", dir.string()},
                {"policy", who},
                {"rate_per_100mi", f.rate.rate},
                {"ci95_per_100mi", {f.rate.ci.lo, f.rate.ci.hi}},
                {"upper_bound_only", f.rate.upper_bound_only}};
  };
  json out = {
      {"event", a.j["event"]},
      {"base", side(a, base)},
      {"candidate", side(b, candidate)},
      {"ratio_defined", r.defined},
      {"ratio", r.ratio},
      {"ratio_ci95", {r.ci.lo, std::isfinite(r.ci.hi) ? json(r.ci.hi) : json(nullptr)}},
      {"verdict", r.verdict},
      {"method", "MOVER on the log scale from the two 95% intervals (independent estimates)"},
      {"speed_on_common_seeds", speed},
      {"notes", notes}};
  return out;
}

json risk_chart_point(const std::filesystem::path& dir) {
  const RiskFile f = read_risk_file(dir);
  const auto file = (dir / "risk.json").string();
  if (f.j["event"] != "at-fault") {
    throw std::runtime_error(file + ": counts " + f.j["event"].dump() +
                             " events; the chart's axis is at-fault contacts (--event at-fault)");
  }
  const json& speed = f.j.value("mean_speed_mph", json());
  if (!speed.is_number() || !(speed.get<double>() > 0.0)) {
    throw std::runtime_error(file +
                             ": no mean_speed_mph (an estimate from before it was kept, or "
                             "with no base run: estimate it again)");
  }
  std::string label = f.j.value("policy", "?");
  const std::string config = f.j.value("config", "");
  if (!config.empty()) label += " " + std::filesystem::path(config).stem().string();
  return {{"folder", dir.string()},
          {"label", label + " (risk)"},
          {"policy", f.j.value("policy", "?")},
          {"config", config},
          {"traffic", f.j.value("traffic", "")},
          {"map", f.j.value("map", json())},
          {"rate_per_100mi", f.rate.rate},
          {"ci95_per_100mi", {f.rate.ci.lo, f.rate.ci.hi}},
          {"upper_bound_only", f.rate.upper_bound_only},
          {"mean_speed_mph", speed},
          {"base_miles", f.j.value("miles", 0.0)}};
}

std::string compare_risk_text(const json& c) {
  std::ostringstream s;
  const auto rate_text = [](const json& side) {
    const json& ci = side["ci95_per_100mi"];
    if (side["upper_bound_only"].get<bool>()) {
      return "0 (at most " + base::fixed_text(ci[1].get<double>(), 4) + ")";
    }
    return base::fixed_text(side["rate_per_100mi"].get<double>(), 4) + " (" +
           base::fixed_text(ci[0].get<double>(), 4) + " to " +
           base::fixed_text(ci[1].get<double>(), 4) + ")";
  };
  s << "# " << c["event"].get<std::string>() << " events per 100 mi\n\n";
  s << "| | policy | rate (95% interval) |\n|---|---|---|\n";
  s << "| base | " << c["base"]["policy"].get<std::string>() << " | " << rate_text(c["base"])
    << " |\n";
  s << "| candidate | " << c["candidate"]["policy"].get<std::string>() << " | "
    << rate_text(c["candidate"]) << " |\n\n";
  const json& ci = c["ratio_ci95"];
  const std::string hi = ci[1].is_null() ? "infinity" : base::fixed_text(ci[1].get<double>(), 3);
  if (c["ratio_defined"].get<bool>()) {
    s << "candidate / base: " << base::fixed_text(c["ratio"].get<double>(), 3) << " (95% "
      << base::fixed_text(ci[0].get<double>(), 3) << " to " << hi
      << "): " << c["verdict"].get<std::string>() << "\n";
  } else {
    s << "candidate / base: at least " << base::fixed_text(ci[0].get<double>(), 3)
      << " (the base saw no event): " << c["verdict"].get<std::string>() << "\n";
  }
  const json& speed = c.value("speed_on_common_seeds", json());
  if (speed.is_object()) {
    const json& sci = speed["ci95_mph"];
    s << "mean speed on the " << speed["seeds"].get<std::size_t>() << " seeds both drove: base "
      << base::fixed_text(speed["base_mph"].get<double>(), 2) << " mph, candidate "
      << base::fixed_text(speed["candidate_mph"].get<double>(), 2)
      << " mph: " << eval::signed_fixed(speed["difference_mph"].get<double>(), 2) << " ("
      << eval::signed_fixed(sci[0].get<double>(), 2) << " to "
      << eval::signed_fixed(sci[1].get<double>(), 2)
      << ", paired): " << speed["verdict"].get<std::string>() << "\n";
  }
  for (const json& n : c["notes"]) s << "note: " << n.get<std::string>() << "\n";
  return s.str();
}

}  // namespace overtake::batch
