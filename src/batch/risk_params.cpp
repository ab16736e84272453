// `overtake risk`: the events it counts, by name, and its parameters (config/risk.json and
// --params): the splitting levels, the stopping rules' block, their checks and their JSON.

#include <optional>
#include <string>

#include "overtake/base/errors.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/resources.hpp"

namespace overtake::batch {

using base::UsageError;
using nlohmann::json;
using run::ConfigError;

std::string RiskEvent::name() const {
  switch (kind) {
    case RiskEventKind::at_fault:
      return "at-fault";
    case RiskEventKind::contact:
      return "contact";
    case RiskEventKind::near_miss:
      return "near-miss";
    case RiskEventKind::incident:
      return std::string(sim::to_string(incident));
  }
  return "?";
}

RiskEvent parse_risk_event(const std::string& name) {
  if (name == "at-fault") return {RiskEventKind::at_fault};
  if (name == "contact") return {RiskEventKind::contact};
  if (name == "near-miss") return {RiskEventKind::near_miss};
  std::string types;
  for (std::size_t t = 0; t < sim::kIncidentTypeCount; ++t) {
    const auto type = static_cast<sim::IncidentType>(t);
    if (name == sim::to_string(type)) return {RiskEventKind::incident, type};
    types += std::string(t ? ", " : "") + std::string(sim::to_string(type));
  }
  throw UsageError("--event: '" + name +
                   "' is none of at-fault, contact, near-miss or a rubric incident type (" + types +
                   ")");
}

// ---------------------------------------------------------------------------------------
// Parameters

eval::SplitLevels RiskParams::levels() const {
  eval::SplitLevels l;
  for (std::size_t j = 0; j < margins_m.size(); ++j) {
    l.thresholds.push_back(-margins_m[j]);
    l.splits.push_back(j < splits.size() ? splits[j] : 1);
  }
  return l;
}

void RiskParams::validate() const {
  const auto bad = [](const std::string& key, const std::string& why) {
    throw ConfigError("risk params: " + key + ": " + why);
  };
  if (margins_m.size() != splits.size()) {
    bad("splits", "one per margin (" + std::to_string(margins_m.size()) + " margins, " +
                      std::to_string(splits.size()) + " splits)");
  }
  if (margins_m.size() > 16) bad("margins_m", "at most 16 levels");
  for (std::size_t j = 0; j < margins_m.size(); ++j) {
    if (!std::isfinite(margins_m[j]) || margins_m[j] < -10.0 || margins_m[j] > 100.0)
      bad("margins_m", "each from -10 to 100 m");
    if (j > 0 && !(margins_m[j] < margins_m[j - 1])) bad("margins_m", "must decrease");
    if (splits[j] < 1 || splits[j] > 50) bad("splits", "each from 1 to 50");
  }
  const auto range = [&](const std::string& key, double v, double lo, double hi) {
    if (!std::isfinite(v) || v < lo || v > hi) {
      bad(key, "must be from " + base::fixed_text(lo, 1) + " to " + base::fixed_text(hi, 1));
    }
  };
  range("score.horizon_s", score.horizon_s, 0.0, 10.0);
  range("score.time_weight_mps", score.time_weight_mps, 0.0, 50.0);
  range("score.lateral_weight", score.lateral_weight, 0.1, 20.0);
  range("score.range_m", score.range_m, 10.0, 1000.0);
  if (max_paths < 1 || max_paths > 10'000'000) bad("max_paths", "must be from 1 to 10000000");
  if (batch_runs < 1 || batch_runs > 10000) bad("batch_runs", "must be from 1 to 10000");
  if (min_runs_with_events < 1) bad("min_runs_with_events", "must be at least 1");
}

namespace {

// Reads `j`'s keys into `p`, refusing unknown keys and wrong types (ConfigError naming
// `source` and the key).
void apply_risk_json(RiskParams& p, const json& j, const std::string& source) {
  const auto fail = [&](const std::string& key, const std::string& why) {
    throw ConfigError(source + ": " + key + ": " + why);
  };
  if (!j.is_object()) fail("(top)", "must be an object");
  const auto number = [&](const json& v, const std::string& key) {
    if (!v.is_number()) fail(key, "must be a number");
    return v.get<double>();
  };
  for (const auto& [key, v] : j.items()) {
    if (key == "score") {
      if (!v.is_object()) fail(key, "must be an object");
      for (const auto& [k, x] : v.items()) {
        const std::string name = "score." + k;
        if (k == "horizon_s") {
          p.score.horizon_s = number(x, name);
        } else if (k == "time_weight_mps") {
          p.score.time_weight_mps = number(x, name);
        } else if (k == "lateral_weight") {
          p.score.lateral_weight = number(x, name);
        } else if (k == "range_m") {
          p.score.range_m = number(x, name);
        } else {
          fail(name, "is not a key of the risk params");
        }
      }
    } else if (key == "margins_m" || key == "splits") {
      if (!v.is_array()) fail(key, "must be a list of numbers");
      std::vector<double> xs;
      for (const json& x : v) xs.push_back(number(x, key));
      if (key == "margins_m") {
        p.margins_m = xs;
      } else {
        p.splits.clear();
        for (double x : xs) {
          if (x != std::floor(x) || std::abs(x) > 1e6) fail(key, "must be whole numbers");
          p.splits.push_back(static_cast<int>(x));
        }
      }
    } else if (key == "max_paths" || key == "batch_runs" || key == "min_runs_with_events") {
      const double x = number(v, key);
      if (x != std::floor(x) || x < 0 || x > 1e9) fail(key, "must be a whole number");
      if (key == "max_paths") p.max_paths = static_cast<std::size_t>(x);
      if (key == "batch_runs") p.batch_runs = static_cast<int>(x);
      if (key == "min_runs_with_events") p.min_runs_with_events = static_cast<int>(x);
    } else if (key == "//" || key.starts_with("_")) {
      // comments
    } else {
      fail(key, "is not a key of the risk params");
    }
  }
  try {
    p.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(source + ": " +
                      std::string(e.what()).substr(std::string("risk params: ").size()));
  }
}

}  // namespace

RiskParams load_risk_params(const std::optional<std::filesystem::path>& path) {
  RiskParams p;
  const auto text = resources::embedded_file("config/risk.json");
  if (!text) throw ConfigError("built-in config/risk.json is missing from this build");
  apply_risk_json(p, run::parse_json_text(*text, "built-in config/risk.json"),
                  "built-in config/risk.json");
  if (path) apply_risk_json(p, run::read_json_file(*path), path->string());
  return p;
}

json risk_params_json(const RiskParams& p) {
  return {{"score",
           {{"horizon_s", p.score.horizon_s},
            {"time_weight_mps", p.score.time_weight_mps},
            {"lateral_weight", p.score.lateral_weight},
            {"range_m", p.score.range_m}}},
          {"margins_m", p.margins_m},
          {"splits", p.splits},
          {"max_paths", p.max_paths},
          {"batch_runs", p.batch_runs},
          {"min_runs_with_events", p.min_runs_with_events}};
}

}  // namespace overtake::batch
