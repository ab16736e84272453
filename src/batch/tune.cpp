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

using tune_detail::bench_of;
using tune_detail::constraints_of;
using tune_detail::map_folder;
using tune_detail::map_label;
using tune_detail::MapChoice;
using tune_detail::maps_of;
using tune_detail::parse_number;
using tune_detail::Placement;
using tune_detail::program_command;
using tune_detail::resolve_target;
using tune_detail::risk_planner;
using tune_detail::run_bench_of;
using tune_detail::run_validation;
using tune_detail::summary_of;
using tune_detail::Target;
using tune_detail::trial_catalog;
using tune_detail::trial_config;

using base::fixed_text;
using base::UsageError;
using nlohmann::json;
namespace fs = std::filesystem;

// ---- numbers and names -----------------------------------------------------------------

std::string join(const std::vector<std::string>& names) {
  return base::join_list(names, ", ");
}

// The counts a trial reports besides overtake::eval's metrics.
const std::vector<std::string>& count_names() {
  static const std::vector<std::string> names = {
      "incidents", "collisions", "at_fault_collisions", "near_misses", "ended_early", "runs"};
  return names;
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

}  // namespace

// ---- parsing ----------------------------------------------------------------------------

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
