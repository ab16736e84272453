// `overtake compare` of two `overtake risk` folders: the ratio of their rates with its
// interval and a verdict (eval::rate_ratio), and what makes them of different roads.

#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>

#include "overtake/base/text.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/eval/splitting.hpp"
#include "overtake/run/config.hpp"

namespace overtake::batch {

using nlohmann::json;

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
  // Runs cut short by the planner's failure: the rate is one of the miles it could drive.
  for (const auto& [f, dir] : {std::pair{&a, &base}, std::pair{&b, &candidate}}) {
    const long ended = f->j.value("runs_ended_by_planner", 0L);
    if (ended > 0) {
      notes.push_back(dir->string() + ": " + std::to_string(ended) + " of " +
                      std::to_string(f->j.value("runs", 0L)) +
                      " runs ended by the planner's failure (their miles until then counted)");
    }
  }
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
  for (const json& n : c["notes"]) s << "note: " << n.get<std::string>() << "\n";
  return s.str();
}

}  // namespace overtake::batch
