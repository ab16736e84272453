// `overtake tune`: the parameters, how a trial gives them to the planner, the figures a trial
// is judged by, the search (NLopt) with its record of trials, and the validation.

#include "overtake/batch/tune.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <regex>
#include <set>

#include <nlopt.hpp>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/eval/metrics.hpp"
#include "overtake/run/config.hpp"
#include "tune_internal.hpp"

namespace overtake::batch {

namespace tune_detail {

std::vector<MapChoice> maps_of(const TuneSpec& spec) {
  return spec.maps.empty() ? std::vector<MapChoice>{std::nullopt} : spec.maps;
}

std::string map_label(const MapChoice& map) {
  return map ? map->string() : std::string("the built-in track");
}

}  // namespace tune_detail

namespace {

using tune_detail::constraints_of;
using tune_detail::map_label;
using tune_detail::MapChoice;
using tune_detail::maps_of;

using base::fixed_text;
using base::UsageError;
using nlohmann::json;
namespace fs = std::filesystem;

// ---- numbers and names -----------------------------------------------------------------

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

bool identifier(std::string_view name) {
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0])) != 0) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
  });
}

std::string join(const std::vector<std::string>& names) {
  return base::join_list(names, ", ");
}

// The counts a trial reports besides overtake::eval's metrics.
const std::vector<std::string>& count_names() {
  static const std::vector<std::string> names = {
      "incidents", "collisions", "at_fault_collisions", "near_misses", "ended_early", "runs"};
  return names;
}

// ---- how a trial gives its parameters to the planner -----------------------------------

// A parameter's place: a config key (as a JSON pointer), a program's placeholder or
// environment variable, a Python keyword.
struct Placement {
  enum class Kind { config, placeholder, environment, keyword } kind = Kind::config;
  std::string key;  ///< the config's JSON pointer, the placeholder's or variable's name
};

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

struct Target {
  std::shared_ptr<const planners::PlannerCatalog> catalog;  ///< holds `entry`
  const planners::PlannerEntry* entry = nullptr;
  json base_config;  ///< built-in policies: the starting config, every key
  /// Built-in policies: the keys the starting config file sets (none without --config). A
  /// trial's config is these and its parameters, so that a key the file leaves to the
  /// defaults is still moved by a knob (planner.reference.assertiveness) a trial turns.
  json file_config = json::object();
  std::vector<Placement> places;
};

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
fs::path map_folder(const fs::path& dir, std::size_t k, std::size_t n) {
  return n == 1 ? dir : dir / ("map-" + std::to_string(k + 1));
}

// The bench of one point of the search: the planner with parameters `x` on `seeds` and `map`,
// into `out` (a built-in policy's config with the values is written beside it, as
// `config_file`).
BenchSpec bench_of(const TuneSpec& spec, const Target& t, const std::vector<double>& x,
                   const std::vector<std::uint64_t>& seeds, const MapChoice& map,
                   const fs::path& out, const fs::path& config_file) {
  fs::create_directories(out);
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

// ---- a trial's figures ------------------------------------------------------------------

json figures_of(const std::vector<json>& rows, const std::string& where) {
  std::vector<eval::RunRow> runs;
  runs.reserve(rows.size());
  for (const json& r : rows) runs.push_back(eval::read_run_row(r, where));
  std::vector<const eval::RunRow*> all;
  for (const auto& r : runs) all.push_back(&r);
  json f = json::object();
  for (const eval::Metric m : eval::all_metrics()) {
    f[std::string(eval::info(m).name)] =
        eval::available(m, all) ? json(eval::value(m, all)) : json(nullptr);
  }
  double incidents = 0, collisions = 0, at_fault = 0, near = 0, ended = 0;
  for (const auto& r : runs) {
    incidents += r.incidents;
    collisions += r.collisions;
    at_fault += r.at_fault_collisions;
    near += r.near_misses;
    ended += r.ended_early ? 1.0 : 0.0;
  }
  f["incidents"] = incidents;
  f["collisions"] = collisions;
  f["at_fault_collisions"] = at_fault;
  f["near_misses"] = near;
  f["ended_early"] = ended;
  f["runs"] = static_cast<double>(runs.size());
  return f;
}

void judge(TuneTrial& trial, const TuneSpec& spec) {
  const json& obj = trial.figures[spec.objective];
  trial.objective = obj.is_number() ? obj.get<double>() : std::numeric_limits<double>::quiet_NaN();
  trial.feasible = std::isfinite(trial.objective);
  trial.violations.clear();
  if (!trial.feasible) trial.violations.push_back(spec.objective + " is not known");
  for (const auto& c : constraints_of(spec)) {
    const json& v = trial.figures[c.figure];
    if (!v.is_number()) {
      trial.feasible = false;
      trial.violations.push_back(c.figure + " is not known");
      continue;
    }
    const double value = v.get<double>();
    if (c.at_most ? value > c.bound : value < c.bound) {
      trial.feasible = false;
      trial.violations.push_back(c.figure + " = " + base::shortest_text(value) +
                                 (c.at_most ? " > " : " < ") + base::shortest_text(c.bound));
    }
  }
}

// How far a trial is from meeting its constraints (0 when it does).
double violation(const TuneTrial& trial, const TuneSpec& spec) {
  double total = 0.0;
  for (const auto& c : constraints_of(spec)) {
    const json& v = trial.figures[c.figure];
    if (!v.is_number()) {
      total += 1e6;
      continue;
    }
    const double value = v.get<double>();
    total += std::max(0.0, c.at_most ? value - c.bound : c.bound - value);
  }
  return total;
}

json trial_json(const TuneTrial& t, const TuneSpec& spec) {
  json params = json::object();
  for (const auto& p : spec.params) params[p.name] = t.params.at(p.name);
  return {{"trial", t.number},
          {"params", params},
          {"objective", std::isfinite(t.objective) ? json(t.objective) : json(nullptr)},
          {"feasible", t.feasible},
          {"violations", t.violations},
          {"figures", t.figures}};
}

// ---- the record ---------------------------------------------------------------------------

std::vector<double> start_point(const TuneSpec& spec, const Target& t);

json manifest_of(const TuneSpec& spec, const Target& t) {
  json params = json::array();
  const std::vector<double> start = start_point(spec, t);
  for (std::size_t i = 0; i < spec.params.size(); ++i) {
    const TuneParam& p = spec.params[i];
    params.push_back({{"name", p.name}, {"low", p.low}, {"high", p.high}, {"start", start[i]}});
  }
  json constraints = json::array();
  for (const auto& c : spec.constraints) {
    constraints.push_back(c.figure + (c.at_most ? "<=" : ">=") + base::shortest_text(c.bound));
  }
  json m = {{"policy", spec.policy},
            {"planner", t.entry->describe()},
            {"params", params},
            {"objective", spec.objective},
            {"constraints", constraints},
            {"traffic", spec.traffic},
            {"seeds", spec.seeds},
            {"minutes", spec.minutes},
            {"map", spec.maps.size() == 1 && spec.maps[0] ? spec.maps[0]->string() : ""},
            {"start_config", t.base_config},
            {"algorithm", spec.algorithm}};
  if (spec.risk) {
    // With a risk (a search without one keeps the manifest it always had).
    const TuneRisk& r = *spec.risk;
    m["risk"] = {{"event", r.event.name()},
                 {"max_per_100mi", r.max_per_100mi ? json(*r.max_per_100mi) : json()},
                 {"hours", r.hours},
                 {"validation_hours", r.validation_hours},
                 {"first_seed", r.first_seed},
                 {"rel_error", r.rel_error}};
  }
  if (spec.maps.size() > 1) {
    // Several maps (a search of one map keeps the manifest it always had).
    m.erase("map");
    m["maps"] = json::array();
    for (const MapChoice& map : spec.maps) m["maps"].push_back(map ? map->string() : "");
  }
  return m;
}

std::vector<TuneTrial> read_trials(const fs::path& file, const TuneSpec& spec) {
  std::vector<TuneTrial> trials;
  std::ifstream in(file);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    json j;
    try {
      j = json::parse(line);
    } catch (const json::exception&) {
      if (in.peek() == std::ifstream::traits_type::eof()) break;  // cut off by a kill
      throw UsageError("--resume: " + file.string() + ":" + std::to_string(number) +
                       " is not a trial (not JSON)");
    }
    TuneTrial t;
    try {
      t.number = j.at("trial").get<int>();
      for (const auto& p : spec.params) t.params[p.name] = j.at("params").at(p.name).get<double>();
      t.figures = j.at("figures");
    } catch (const json::exception& e) {
      throw UsageError("--resume: " + file.string() + ":" + std::to_string(number) +
                       " is not a trial of this search (" + e.what() + ")");
    }
    if (t.number != static_cast<int>(trials.size()) + 1) {
      throw UsageError("--resume: " + file.string() + ":" + std::to_string(number) + " is trial " +
                       std::to_string(t.number) + ", expected " +
                       std::to_string(trials.size() + 1));
    }
    judge(t, spec);
    t.resumed = true;
    trials.push_back(std::move(t));
  }
  return trials;
}

void append_line(const fs::path& file, const std::string& line) {
  std::ofstream out(file, std::ios::app | std::ios::binary);
  out << line << '\n';
  out.flush();
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

std::string trial_folder_name(int number) {
  std::string n = std::to_string(number);
  return std::string(n.size() < 4 ? 4 - n.size() : 0, '0') + n;
}

// The planner whose risk a bench of `x` into `dir` runs (its config file written there).
tune_detail::RiskPlanner risk_planner(const TuneSpec& spec, const Target& t,
                                      const std::vector<double>& x, const fs::path& config_file) {
  const bool builtin = t.entry->kind == planners::PlannerKind::builtin;
  return {spec.policy, trial_catalog(t, spec, x), builtin ? config_file : spec.config};
}

// ---- the search ---------------------------------------------------------------------------

class Search {
 public:
  Search(const TuneSpec& spec, Target target, const std::atomic<bool>* stop,
         const std::function<void(const TuneProgress&)>& progress)
      : spec_(spec), target_(std::move(target)), stop_(stop), progress_(progress) {}

  std::vector<TuneTrial> trials;
  bool interrupted = false;
  bool budget_spent = false;

  // The trial of these parameters: one already run (the same numbers: the optimiser asks
  // again, or a resumed search asks what it asked before), or a new one.
  const TuneTrial* evaluate(const std::vector<double>& x) {
    for (const auto& t : trials) {
      if (params_vector(t) == x) return &t;
    }
    if (static_cast<int>(trials.size()) >= spec_.trials) {
      budget_spent = true;
      return nullptr;
    }
    return run_trial(x);
  }

  [[nodiscard]] std::vector<double> params_vector(const TuneTrial& t) const {
    std::vector<double> x;
    for (const auto& p : spec_.params) x.push_back(t.params.at(p.name));
    return x;
  }

  // What the optimiser minimises: the objective (negated when higher is better) of a
  // feasible trial; past every feasible value, growing with the violation, for the others.
  [[nodiscard]] double loss(const TuneTrial& t) const {
    if (!t.feasible) return 1e12 + violation(t, spec_) * 1e3;
    return tune_figure_higher_is_better(spec_.objective) ? -t.objective : t.objective;
  }

  [[nodiscard]] std::optional<int> best() const {
    std::optional<int> b;
    for (const auto& t : trials) {
      if (!t.feasible) continue;
      if (!b || loss(t) < loss(trials[static_cast<std::size_t>(*b - 1)])) b = t.number;
    }
    return b;
  }

 private:
  const TuneTrial* run_trial(const std::vector<double>& x) {
    if (stop_ != nullptr && stop_->load()) {
      interrupted = true;
      return nullptr;
    }
    TuneTrial t;
    t.number = static_cast<int>(trials.size()) + 1;
    for (std::size_t i = 0; i < x.size(); ++i) t.params[spec_.params[i].name] = x[i];
    const fs::path dir = spec_.out / kTuneTrialsFolder / trial_folder_name(t.number);
    std::error_code ignored;
    // A trial cut off by Ctrl-C starts again here; on Slurm its array is taken up again (its
    // tasks may still run, writing into the folder).
    if (!spec_.run_bench_elsewhere) fs::remove_all(dir, ignored);
    const auto started = std::chrono::steady_clock::now();
    const std::vector<MapChoice> maps = maps_of(spec_);
    std::vector<json> rows;
    for (std::size_t k = 0; k < maps.size(); ++k) {
      const fs::path out = map_folder(dir, k, maps.size());
      const BenchSpec b =
          bench_of(spec_, target_, x, spec_.seeds, maps[k], out, dir / "config.json");
      const bool cut_off = run_bench_of(spec_, b, stop_, [&](const BenchProgress& p) {
        if (!progress_) return;
        TuneProgress tp;
        tp.trial = t.number;
        tp.trials = spec_.trials;
        tp.runs_done = k * p.total + p.done;
        tp.runs_total = maps.size() * p.total;
        if (const auto bi = best()) tp.best = trials[static_cast<std::size_t>(*bi - 1)].objective;
        tp.wall_s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
        progress_(tp);
      });
      if (cut_off) {
        interrupted = true;
        return nullptr;
      }
      for (json& r : load_bench_runs(out)) rows.push_back(std::move(r));
    }
    t.figures = figures_of(rows, (dir / kBenchRunsFile).string());
    if (spec_.risk) {
      const auto risk = tune_detail::trial_risk(
          spec_, risk_planner(spec_, target_, x, dir / "config.json"), dir / "risk", stop_);
      if (!risk) {
        interrupted = true;
        return nullptr;
      }
      t.figures.update(*risk);
    }
    judge(t, spec_);
    append_line(spec_.out / kTuneTrialsFile, trial_json(t, spec_).dump());
    trials.push_back(std::move(t));
    return &trials.back();
  }

  const TuneSpec& spec_;
  Target target_;
  const std::atomic<bool>* stop_;
  const std::function<void(const TuneProgress&)>& progress_;
};

nlopt::algorithm algorithm_of(const std::string& name) {
  if (name == "sbplx") return nlopt::LN_SBPLX;
  if (name == "neldermead") return nlopt::LN_NELDERMEAD;
  if (name == "bobyqa") return nlopt::LN_BOBYQA;
  if (name == "cobyla") return nlopt::LN_COBYLA;
  if (name == "direct") return nlopt::GN_DIRECT_L;
  if (name == "crs2") return nlopt::GN_CRS2_LM;
  throw UsageError("--algorithm: unknown '" + name + "' (" +
                   base::join_list(tune_algorithm_names(), ", ") + ")");
}

std::vector<double> start_point(const TuneSpec& spec, const Target& t) {
  std::vector<double> x;
  for (std::size_t i = 0; i < spec.params.size(); ++i) {
    const TuneParam& p = spec.params[i];
    if (p.start) {
      x.push_back(*p.start);
    } else if (t.entry->kind == planners::PlannerKind::builtin) {
      x.push_back(t.base_config[json::json_pointer(t.places[i].key)].get<double>());
    } else {
      x.push_back((p.low + p.high) / 2.0);
    }
  }
  return x;
}

// `value` to 10 significant digits: a trial's parameters as a user would type them (0.9, not
// 0.9000000000000001 from the scaling), in its rows, best.json and a program's command.
double round_to_digits(double value) {
  std::array<char, 32> buf{};
  const auto written =
      std::to_chars(buf.data(), buf.data() + buf.size(), value, std::chars_format::general, 10);
  double out = value;
  std::from_chars(buf.data(), written.ptr, out);
  return out;
}

// The seed of NLopt's random numbers (crs2's population).
constexpr unsigned long kCrs2Seed = 20261128;

// Runs NLopt on the unit cube (each parameter scaled to [0, 1]) from the start.
std::string optimise(Search& search, const TuneSpec& spec, const std::vector<double>& start) {
  const std::size_t n = spec.params.size();
  const auto to_x = [&](const std::vector<double>& u) {
    std::vector<double> x(n);
    for (std::size_t i = 0; i < n; ++i) {
      const TuneParam& p = spec.params[i];
      x[i] = i < u.size() && std::abs(u[i] - (start[i] - p.low) / (p.high - p.low)) < 1e-15
                 ? start[i]  // the start exactly, not a number that rounds near it
                 : std::clamp(round_to_digits(p.low + u[i] * (p.high - p.low)), p.low, p.high);
    }
    return x;
  };
  std::vector<double> u(n);
  for (std::size_t i = 0; i < n; ++i) {
    const TuneParam& p = spec.params[i];
    u[i] = (start[i] - p.low) / (p.high - p.low);
  }
  nlopt::opt opt(algorithm_of(spec.algorithm), static_cast<unsigned>(n));
  opt.set_lower_bounds(std::vector<double>(n, 0.0));
  opt.set_upper_bounds(std::vector<double>(n, 1.0));
  opt.set_initial_step(0.25);
  opt.set_xtol_abs(1e-3);
  opt.set_maxeval(std::max(spec.trials * 20, 100));  // asks for trials already run are free
  // CRS2's random points from a fixed seed: the same search on every run (and on --resume).
  nlopt::srand(kCrs2Seed);
  // NLopt turns an exception in the objective into its own failure: a trial's error is kept
  // here and thrown again once the optimiser has returned.
  struct Data {
    Search* search;
    const std::function<std::vector<double>(const std::vector<double>&)>* to_x;
    std::exception_ptr error;
  };
  const std::function<std::vector<double>(const std::vector<double>&)> convert = to_x;
  Data data{&search, &convert, nullptr};
  opt.set_min_objective(
      [](const std::vector<double>& uu, std::vector<double>&, void* d) -> double {
        auto* state = static_cast<Data*>(d);
        const TuneTrial* t = nullptr;
        try {
          t = state->search->evaluate((*state->to_x)(uu));
        } catch (...) {
          state->error = std::current_exception();
        }
        if (t == nullptr) throw nlopt::forced_stop();
        return state->search->loss(*t);
      },
      &data);
  double value = 0.0;
  try {
    const nlopt::result r = opt.optimize(u, value);
    switch (r) {
      case nlopt::XTOL_REACHED:
        return "the steps became smaller than 0.1% of each range";
      case nlopt::FTOL_REACHED:
        return "the objective stopped improving";
      case nlopt::MAXEVAL_REACHED:
        return "the optimiser asked for the same trials again and again";
      default:
        return "the optimiser ended (" + std::to_string(static_cast<int>(r)) + ")";
    }
  } catch (const nlopt::forced_stop&) {
    if (data.error) std::rethrow_exception(data.error);
    if (search.interrupted) return "interrupted";
    return "the budget of " + std::to_string(spec.trials) + " trials";
  } catch (const nlopt::roundoff_limited&) {
    return "the optimiser reached the limit of its arithmetic";
  }
}

// ---- the validation and the reports ---------------------------------------------------------

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

}  // namespace

// ---- parsing ----------------------------------------------------------------------------

TuneParam parse_tune_param(const std::string& text) {
  const auto eq = text.find('=');
  const auto bad = [&](const std::string& why) {
    return UsageError("--param: '" + text + "': " + why +
                      " (expected NAME=LOW:HIGH or NAME=LOW:HIGH@START)");
  };
  if (eq == std::string::npos) throw bad("no '='");
  TuneParam p;
  p.name = text.substr(0, eq);
  if (!valid_param_name(p.name)) throw bad("'" + p.name + "' is not a parameter name");
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

TuneConstraint parse_tune_constraint(const std::string& text) {
  TuneConstraint c;
  std::size_t at = text.find("<=");
  c.at_most = at != std::string::npos;
  if (!c.at_most) at = text.find(">=");
  if (at == std::string::npos) {
    throw UsageError("--constraint: '" + text + "' is not NAME<=VALUE or NAME>=VALUE");
  }
  c.figure = text.substr(0, at);
  const auto& names = tune_figure_names();
  if (std::find(names.begin(), names.end(), c.figure) == names.end()) {
    throw UsageError("--constraint: '" + c.figure + "' is not a figure (" + join(names) + ")");
  }
  const auto bound = parse_number(text.substr(at + 2));
  if (!bound) throw UsageError("--constraint: '" + text.substr(at + 2) + "' is not a number");
  c.bound = *bound;
  return c;
}

const std::vector<std::string>& tune_figure_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const eval::Metric m : eval::all_metrics()) n.emplace_back(eval::info(m).name);
    for (const auto& c : count_names()) n.push_back(c);
    for (const auto& c : tune_risk_figure_names()) n.push_back(c);
    return n;
  }();
  return names;
}

bool tune_figure_higher_is_better(const std::string& name) {
  if (const auto m = eval::parse_metric(name)) return eval::info(*m).higher_is_better;
  return false;  // the counts: fewer is better (runs is not an objective)
}

const std::vector<std::string>& tune_algorithm_names() {
  static const std::vector<std::string> names = {"sbplx",  "neldermead", "bobyqa",
                                                 "cobyla", "direct",     "crs2"};
  return names;
}

// ---- the whole search ---------------------------------------------------------------------

void check_tune_spec(const TuneSpec& spec) {
  if (spec.params.empty()) throw UsageError("--param: name at least one parameter to search");
  std::set<std::string> seen;
  for (const auto& p : spec.params) {
    if (!seen.insert(p.name).second) {
      throw UsageError("--param: '" + p.name + "' is given twice");
    }
  }
  const auto& names = tune_figure_names();
  if (std::find(names.begin(), names.end(), spec.objective) == names.end() ||
      spec.objective == "runs") {
    throw UsageError("--objective: '" + spec.objective + "' is not a figure (" + join(names) + ")");
  }
  (void)algorithm_of(spec.algorithm);
  if (spec.seeds.empty()) throw UsageError("--seeds: no training seeds");
  for (const auto s : spec.validation_seeds) {
    if (std::find(spec.seeds.begin(), spec.seeds.end(), s) != spec.seeds.end()) {
      throw UsageError("--validate-seeds: seed " + std::to_string(s) +
                       " is also a training seed; held-out seeds must be others");
    }
  }
  if (spec.trials < 1 || spec.trials > kMaxTuneTrials) {
    throw UsageError("--trials must be between 1 and " + std::to_string(kMaxTuneTrials) + " (got " +
                     std::to_string(spec.trials) + ")");
  }
  tune_detail::check_tune_risk(spec);
  const Target t = resolve_target(spec);
  const std::vector<double> start = start_point(spec, t);
  for (std::size_t i = 0; i < start.size(); ++i) {
    const TuneParam& p = spec.params[i];
    if (start[i] < p.low || start[i] > p.high) {
      throw UsageError("--param: " + p.name + " starts at " + base::shortest_text(start[i]) +
                       " (its value in the config), outside its range " +
                       base::shortest_text(p.low) + ":" + base::shortest_text(p.high) +
                       "; widen the range or give @START");
    }
  }
  if (t.entry->kind == planners::PlannerKind::python ||
      t.entry->kind == planners::PlannerKind::plugin) {
    std::map<std::string, double> keywords;
    for (std::size_t i = 0; i < start.size(); ++i) keywords[spec.params[i].name] = start[i];
    try {
      (void)t.entry->with_params(keywords);
    } catch (const std::exception& e) {
      throw UsageError(std::string("--param: ") + e.what());
    }
  }
  if (t.entry->kind == planners::PlannerKind::builtin) {
    // Every trial's config must be one the planner takes: the corners of the box are checked.
    for (std::size_t i = 0; i < start.size(); ++i) {
      for (const double v : {spec.params[i].low, spec.params[i].high}) {
        std::vector<double> x = start;
        x[i] = v;
        try {
          (void)run::apply_config_json(run::default_config(), trial_config(t, x), "the trial");
        } catch (const run::ConfigError& e) {
          throw UsageError("--param: " + spec.params[i].name + "=" + base::shortest_text(v) +
                           " is not a value the planner takes: " + e.what());
        }
      }
    }
  }
  for (const MapChoice& map : maps_of(spec)) {
    BenchSpec b;
    b.policies = {spec.policy};
    b.traffic = spec.traffic;
    b.seeds = spec.seeds;
    b.minutes = spec.minutes;
    b.map = map;
    b.config = spec.config;
    b.planners = spec.planners;
    b.jobs = spec.jobs;
    check_bench_spec(b);
  }
}

TuneOutcome run_tune(const TuneSpec& spec, const std::atomic<bool>* stop,
                     const std::function<void(const TuneProgress&)>& progress) {
  const auto started = std::chrono::steady_clock::now();
  check_tune_spec(spec);
  Target target = resolve_target(spec);
  const json manifest = manifest_of(spec, target);
  const fs::path manifest_file = spec.out / kTuneManifestFile;
  const fs::path trials_file = spec.out / kTuneTrialsFile;
  Search search(spec, target, stop, progress);
  if (spec.resume && fs::exists(manifest_file)) {
    const json before = run::read_json_file(manifest_file);
    if (before != manifest) {
      throw UsageError("--resume: " + manifest_file.string() +
                       " is another search (its policy, parameters, objective, constraints, "
                       "seeds, maps or starting config differ); start a new --out");
    }
    search.trials = read_trials(trials_file, spec);
    // A line cut off by a kill is dropped: the file is written again from the trials.
    std::string text;
    for (const auto& t : search.trials) text += trial_json(t, spec).dump() + "\n";
    base::write_file_atomic(trials_file, text);
  } else {
    if (fs::exists(manifest_file) || fs::exists(trials_file)) {
      throw UsageError("--out: " + spec.out.string() +
                       " holds a search already; --resume goes on with it, or choose another "
                       "--out");
    }
    if (!spec.force && fs::exists(spec.out) && !fs::is_empty(spec.out)) {
      throw UsageError("--out: " + spec.out.string() +
                       " is not empty and holds no search; choose another --out (or --force)");
    }
    fs::create_directories(spec.out);
    base::write_file_atomic(manifest_file, manifest.dump(2) + "\n");
    base::write_file_atomic(trials_file, "");
  }

  TuneOutcome o;
  const std::vector<double> start = start_point(spec, target);
  if (search.evaluate(start) != nullptr && !search.interrupted) {
    o.stop_reason = optimise(search, spec, start);
  } else {
    o.stop_reason = search.interrupted ? "interrupted" : "the budget";
  }
  o.interrupted = search.interrupted;
  o.trials = search.trials;
  o.best = search.best();
  if (o.best) {
    const TuneTrial& b = o.trials[static_cast<std::size_t>(*o.best - 1)];
    const std::vector<double> x = search.params_vector(b);
    if (target.entry->kind == planners::PlannerKind::builtin) {
      // Only the keys searched: a file to give --config (over the starting config, if any).
      json overrides = json::object();
      for (std::size_t i = 0; i < x.size(); ++i) {
        overrides[json::json_pointer(target.places[i].key)] = x[i];
      }
      o.best_config = overrides;
    } else {
      o.best_config = json::object();
      for (const auto& [k, v] : b.params) o.best_config[k] = v;
      if (target.entry->kind == planners::PlannerKind::program) {
        o.best_command = program_command(target, x);
      }
    }
    base::write_file_atomic(spec.out / kTuneBestFile, o.best_config.dump(2) + "\n");
    if (!o.interrupted && !spec.validation_seeds.empty()) {
      bool interrupted = false;
      o.validations = run_validation(spec, target, start, x, stop, interrupted);
      o.interrupted = interrupted;
    }
  }
  o.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  o.summary_markdown = summary_of(spec, o);
  base::write_file_atomic(spec.out / kTuneSummaryFile, o.summary_markdown);
  base::write_file_atomic(spec.out / kTunePageFile, tune_page(spec, o));
  return o;
}

}  // namespace overtake::batch
