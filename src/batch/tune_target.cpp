// `overtake tune`: how a trial gives its parameters to the planner: a built-in policy's config
// keys, a program's placeholders or environment variables, a Python planner's or a plugin's
// keywords.

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <functional>
#include <map>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/run/config.hpp"
#include "tune_internal.hpp"

namespace overtake::batch::tune_detail {

std::optional<double> parse_number(std::string_view text) {
  double v = 0.0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (r.ec != std::errc{} || r.ptr != text.data() + text.size() || !std::isfinite(v)) {
    return std::nullopt;
  }
  return v;
}

bool valid_param_name(std::string_view name) {
  if (name.empty()) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.';
  });
}

namespace {

using base::UsageError;
using nlohmann::json;

bool identifier(std::string_view name) {
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0])) != 0) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
  });
}

std::string join(const std::vector<std::string>& names) {
  return base::join_list(names, ", ");
}

// Finds the config key a parameter names: the full dotted path, or a unique ending of one
// ("behaviour.min_gap_m"); only the planner's keys (the world is what a planner is tested on).
std::string config_pointer(const json& config, const std::string& name) {
  std::vector<std::string> paths;
  const std::function<void(const json&, const std::string&)> walk = [&](const json& j,
                                                                        const std::string& at) {
    for (const auto& [k, v] : j.items()) {
      const std::string path = at.empty() ? k : at + "." + k;
      if (v.is_object()) {
        walk(v, path);
      } else if (v.is_number()) {
        paths.push_back(path);
      }
    }
  };
  walk(config, "");
  std::vector<std::string> found;
  for (const auto& p : paths) {
    if (p == name) {
      found = {p};
      break;
    }
    if (p.size() > name.size() && p.ends_with(name) && p[p.size() - name.size() - 1] == '.') {
      found.push_back(p);
    }
  }
  if (found.empty()) {
    // A name that ends keys only part-way through their last word ("weight" of
    // "proximity_weight"): name them, so the user picks one.
    std::vector<std::string> near;
    for (const auto& p : paths) {
      if (p.ends_with(name) && p.starts_with("planner.")) near.push_back(p);
    }
    if (!near.empty()) {
      throw UsageError("--param: '" + name + "' is no key's whole name, and is the ending of " +
                       std::to_string(near.size()) + " (" + join(near) +
                       "): give one of them, or a unique ending from a '.'");
    }
    throw UsageError("--param: '" + name +
                     "' is not a numeric key of the config (`overtake config` lists them; a key "
                     "may be named by its full path or a unique ending)");
  }
  if (found.size() > 1) {
    std::string list;
    for (const auto& f : found) list += (list.empty() ? "" : ", ") + f;
    throw UsageError("--param: '" + name + "' names several config keys (" + list +
                     "): give more of its path");
  }
  if (!found[0].starts_with("planner.")) {
    throw UsageError("--param: '" + found[0] +
                     "' is not the planner's: tune searches a planner's parameters, and the "
                     "world, road and car are what planners are tested on");
  }
  std::string pointer = "/" + found[0];
  std::replace(pointer.begin(), pointer.end(), '.', '/');
  return pointer;
}

}  // namespace

Target resolve_target(const TuneSpec& spec) {
  Target t;
  t.catalog = spec.planners ? spec.planners : std::make_shared<const planners::PlannerCatalog>();
  t.entry = &t.catalog->require(spec.policy);
  using planners::PlannerKind;
  switch (t.entry->kind) {
    case PlannerKind::builtin:
      t.base_config = run::config_to_json(run::load_config(spec.config));
      if (spec.config) t.file_config = run::read_json_file(*spec.config);
      for (const auto& p : spec.params) {
        t.places.push_back({Placement::Kind::config, config_pointer(t.base_config, p.name)});
      }
      break;
    case PlannerKind::program:
      for (const auto& p : spec.params) {
        const std::string placeholder = "{" + p.name + "}";
        if (t.entry->program->command.find(placeholder) != std::string::npos) {
          t.places.push_back({Placement::Kind::placeholder, placeholder});
        } else if (identifier(p.name)) {
          t.places.push_back({Placement::Kind::environment, p.name});
        } else {
          throw UsageError("--param: '" + p.name + "' is neither a placeholder {" + p.name +
                           "} of the planner program's command nor a name an environment "
                           "variable can have");
        }
      }
      break;
    case PlannerKind::python:
    case PlannerKind::plugin:
      if (!t.entry->with_keywords) {
        throw UsageError("--param: " + t.entry->label() + " cannot be given parameters");
      }
      for (const auto& p : spec.params) {
        if (t.entry->kind == PlannerKind::python && !identifier(p.name)) {
          throw UsageError("--param: '" + p.name + "' cannot be a Python keyword argument");
        }
        t.places.push_back({Placement::Kind::keyword, p.name});
      }
      break;
  }
  return t;
}

// The command of a program with the trial's parameters: placeholders replaced, variables set
// before it.
std::string program_command(const Target& t, const std::vector<double>& x) {
  std::string command = t.entry->program->command;
  std::string env;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Placement& p = t.places[i];
    if (p.kind == Placement::Kind::placeholder) {
      std::size_t at = 0;
      while ((at = command.find(p.key, at)) != std::string::npos) {
        command.replace(at, p.key.size(), base::shortest_text(x[i]));
        at += 1;
      }
    } else if (p.kind == Placement::Kind::environment) {
      env += p.key + "=" + base::shortest_text(x[i]) + " ";
    }
  }
  return env.empty() ? command : "export " + env + "&& " + command;
}

json trial_config(const Target& t, const std::vector<double>& x) {
  json c = t.file_config;
  for (std::size_t i = 0; i < x.size(); ++i) c[json::json_pointer(t.places[i].key)] = x[i];
  return c;
}

// The catalog a trial's bench runs: the tuned planner with the trial's parameters.
std::shared_ptr<const planners::PlannerCatalog> trial_catalog(const Target& t, const TuneSpec& spec,
                                                              const std::vector<double>& x) {
  using planners::PlannerKind;
  if (t.entry->kind == PlannerKind::builtin) return spec.planners;
  auto catalog = std::make_shared<planners::PlannerCatalog>();
  planners::PlannerEntry e = *t.entry;
  if (e.kind == PlannerKind::program) {
    e.program->command = program_command(t, x);
    e.source = e.program->command;
    catalog->add(std::move(e), planners::flag_of(PlannerKind::program));
  } else {
    std::map<std::string, double> keywords;
    for (std::size_t i = 0; i < x.size(); ++i) keywords[t.places[i].key] = x[i];
    catalog->add(e.with_params(keywords), planners::flag_of(e.kind));
  }
  return catalog;
}

// Where the bench of map `k` of `n` goes under a trial's (or a validation's) folder: the
// folder itself for one map, map-1/, map-2/, ... for several.
std::filesystem::path map_folder(const std::filesystem::path& dir, std::size_t k, std::size_t n) {
  return n == 1 ? dir : dir / ("map-" + std::to_string(k + 1));
}

// The bench of one point of the search: the planner with parameters `x` on `seeds` and `map`,
// into `out` (a built-in policy's config with the values is written beside it, as
// `config_file`).
BenchSpec bench_of(const TuneSpec& spec, const Target& t, const std::vector<double>& x,
                   const std::vector<std::uint64_t>& seeds, const MapChoice& map,
                   const std::filesystem::path& out, const std::filesystem::path& config_file) {
  std::filesystem::create_directories(out);
  BenchSpec b;
  b.policies = {spec.policy};
  b.traffic = spec.traffic;
  b.seeds = seeds;
  b.minutes = spec.minutes;
  b.map = map;
  b.jobs = spec.jobs;
  b.out = out;
  b.planners = trial_catalog(t, spec, x);
  if (t.entry->kind == planners::PlannerKind::builtin) {
    base::write_file_atomic(config_file, trial_config(t, x).dump(2) + "\n");
    b.config = config_file;
  } else {
    b.config = spec.config;
  }
  return b;
}

// Runs bench `b` here, or where the spec says (Slurm); true when it was interrupted.
bool run_bench_of(const TuneSpec& spec, const BenchSpec& b, const std::atomic<bool>* stop,
                  const std::function<void(const BenchProgress&)>& progress) {
  if (spec.run_bench_elsewhere) return spec.run_bench_elsewhere(b, stop);
  return run_bench(b, stop, progress).interrupted;
}

// The planner whose risk a bench of `x` into `dir` runs (its config file written there).
RiskPlanner risk_planner(const TuneSpec& spec, const Target& t, const std::vector<double>& x,
                         const std::filesystem::path& config_file) {
  const bool builtin = t.entry->kind == planners::PlannerKind::builtin;
  return {spec.policy, trial_catalog(t, spec, x), builtin ? config_file : spec.config};
}

}  // namespace overtake::batch::tune_detail

namespace overtake::batch {

using base::UsageError;
using tune_detail::parse_number;

TuneParam parse_tune_param(const std::string& text) {
  const auto eq = text.find('=');
  const auto bad = [&](const std::string& why) {
    return UsageError("--param: '" + text + "': " + why +
                      " (expected NAME=LOW:HIGH or NAME=LOW:HIGH@START)");
  };
  if (eq == std::string::npos) throw bad("no '='");
  TuneParam p;
  p.name = text.substr(0, eq);
  if (!tune_detail::valid_param_name(p.name)) throw bad("'" + p.name + "' is not a parameter name");
  std::string range = text.substr(eq + 1);
  if (const auto at = range.find('@'); at != std::string::npos) {
    p.start = parse_number(range.substr(at + 1));
    if (!p.start) throw bad("the start '" + range.substr(at + 1) + "' is not a number");
    range = range.substr(0, at);
  }
  const auto colon = range.find(':');
  if (colon == std::string::npos) throw bad("no ':' between LOW and HIGH");
  const auto low = parse_number(range.substr(0, colon));
  const auto high = parse_number(range.substr(colon + 1));
  if (!low || !high) throw bad("LOW and HIGH must be numbers");
  if (!(*low < *high)) throw bad("LOW must be below HIGH");
  p.low = *low;
  p.high = *high;
  if (p.start && (*p.start < p.low || *p.start > p.high)) throw bad("START is outside the range");
  return p;
}

}  // namespace overtake::batch
