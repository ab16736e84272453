#include "calibration.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "overtake/eval/stats.hpp"

namespace overtake::eval::calibration {
namespace {

double sum(const std::vector<double>& v) {
  double s = 0.0;
  for (const double x : v) s += x;
  return s;
}

std::vector<double> pick(const std::vector<double>& v, const std::vector<std::size_t>& idx,
                         double scale = 1.0) {
  std::vector<double> out(idx.size());
  for (std::size_t k = 0; k < idx.size(); ++k) out[k] = v[idx[k]] * scale;
  return out;
}

double normal(core::Rng& rng) {
  const double u1 = 1.0 - rng.uniform01();
  const double u2 = rng.uniform01();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

}  // namespace

Populations load(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  if (!in) throw std::runtime_error(csv.string() + ": cannot be read");
  Populations out;
  std::string line;
  std::getline(in, line);  // the header
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    std::stringstream ss(line);
    std::vector<std::string> f;
    std::string cell;
    while (std::getline(ss, cell, ',')) f.push_back(cell);
    if (f.size() != 10) {
      throw std::runtime_error(csv.string() + ":" + std::to_string(number) + ": 10 fields wanted");
    }
    Population& p = out[{f[0], f[1], f[2]}];
    p.set = f[0];
    p.policy = f[1];
    p.traffic = f[2];
    p.seed.push_back(std::stoull(f[3]));
    p.miles.push_back(std::stod(f[4]));
    p.hours.push_back(std::stod(f[5]));
    p.incidents.push_back(std::stod(f[6]));
    p.collisions.push_back(std::stod(f[7]));
    p.at_fault.push_back(std::stod(f[8]));
    p.near_misses.push_back(std::stod(f[9]));
  }
  return out;
}

const Populations& rows() {
  static const Populations all =
      load(std::filesystem::path(OVERTAKE_SOURCE_DIR) / "tests/data/calibration/bench_rows.csv");
  return all;
}

const Population& population(const std::string& set, const std::string& policy,
                             const std::string& traffic) {
  const auto it = rows().find({set, policy, traffic});
  if (it == rows().end())
    throw std::runtime_error("no rows of " + set + " " + policy + " " + traffic);
  return it->second;
}

const char* name(Rate r) {
  switch (r) {
    case Rate::incidents:
      return "incidents";
    case Rate::collisions:
      return "collisions";
    case Rate::at_fault:
      return "at-fault collisions";
    case Rate::near_misses:
      return "near misses";
  }
  return "?";
}

const std::vector<double>& counts(const Population& p, Rate r) {
  switch (r) {
    case Rate::incidents:
      return p.incidents;
    case Rate::collisions:
      return p.collisions;
    case Rate::at_fault:
      return p.at_fault;
    case Rate::near_misses:
      return p.near_misses;
  }
  return p.incidents;
}

double true_speed(const Population& p) {
  return sum(p.miles) / sum(p.hours);
}

double true_rate(const Population& p, Rate r) {
  return 100.0 * sum(counts(p, r)) / sum(p.miles);
}

double dispersion(const Population& p, Rate r) {
  const std::vector<double>& c = counts(p, r);
  const double mean = sum(c) / static_cast<double>(c.size());
  if (mean <= 0.0 || c.size() < 2) return 0.0;
  double ss = 0.0;
  for (const double x : c) ss += (x - mean) * (x - mean);
  return ss / static_cast<double>(c.size() - 1) / mean;
}

double top_share(const Population& p, Rate r) {
  std::vector<double> c = counts(p, r);
  const double total = sum(c);
  if (total <= 0.0) return 0.0;
  std::sort(c.begin(), c.end(), std::greater<>());
  const auto top = std::max<std::size_t>(1, (c.size() + 19) / 20);
  double held = 0.0;
  for (std::size_t i = 0; i < top; ++i) held += c[i];
  return held / total;
}

std::vector<std::size_t> draw(core::Rng& rng, std::size_t population, std::size_t n) {
  std::vector<std::size_t> idx(n);
  for (std::size_t& i : idx) i = static_cast<std::size_t>(rng.next() % population);
  return idx;
}

double speed_coverage(const Population& p, std::size_t n, int draws, std::uint64_t seed,
                      int resamples) {
  core::Rng rng(seed);
  const double truth = true_speed(p);
  int covered = 0;
  for (int d = 0; d < draws; ++d) {
    const auto idx = draw(rng, p.size(), n);
    BootstrapOptions o;
    o.resamples = resamples;
    o.seed = rng.next();
    const Interval ci = mean_interval(pick(p.miles, idx), pick(p.hours, idx), o);
    if (ci.lo <= truth && truth <= ci.hi) ++covered;
  }
  return static_cast<double>(covered) / draws;
}

double rate_coverage(const Population& p, Rate r, std::size_t n, int draws, std::uint64_t seed) {
  core::Rng rng(seed);
  const double truth = true_rate(p, r);
  int covered = 0;
  for (int d = 0; d < draws; ++d) {
    const auto idx = draw(rng, p.size(), n);
    const RateInterval ci = rate_interval(pick(counts(p, r), idx), pick(p.miles, idx), 100.0);
    if (ci.ci.lo <= truth && truth <= ci.ci.hi) ++covered;
  }
  return static_cast<double>(covered) / draws;
}

double speed_difference_coverage(const Population& a, const Population& b, std::size_t n, int draws,
                                 std::uint64_t seed, int resamples) {
  core::Rng rng(seed);
  const double truth = true_speed(a) - true_speed(b);
  int covered = 0;
  for (int d = 0; d < draws; ++d) {
    const auto idx = draw(rng, a.size(), n);
    const auto na = pick(a.miles, idx), da = pick(a.hours, idx);
    const auto nb = pick(b.miles, idx), db = pick(b.hours, idx);
    BootstrapOptions o;
    o.resamples = resamples;
    o.seed = rng.next();
    const Interval ci = mean_difference_interval({na, da, nb, db}, o);
    if (ci.lo <= truth && truth <= ci.hi) ++covered;
  }
  return static_cast<double>(covered) / draws;
}

double rate_difference_coverage(const Population& a, const Population& b, Rate r, std::size_t n,
                                int draws, std::uint64_t seed) {
  core::Rng rng(seed);
  const double truth = true_rate(a, r) - true_rate(b, r);
  int covered = 0;
  for (int d = 0; d < draws; ++d) {
    const auto idx = draw(rng, a.size(), n);
    const auto ya = pick(counts(a, r), idx), ma = pick(a.miles, idx);
    const auto yb = pick(counts(b, r), idx), mb = pick(b.miles, idx);
    const Interval ci = rate_difference_interval({ya, ma, yb, mb}, 100.0);
    if (ci.lo <= truth && truth <= ci.hi) ++covered;
  }
  return static_cast<double>(covered) / draws;
}

RunRow run_row(const Population& p, std::size_t i, std::uint64_t seed, double add_mph,
               double mile_scale) {
  RunRow r;
  r.index = static_cast<std::size_t>(seed);
  r.policy = p.policy;
  r.traffic = p.traffic;
  r.seed = seed;
  r.map_hash = "calibration";
  r.seconds = p.hours[i] * 3600.0;
  r.miles = (p.miles[i] + add_mph * p.hours[i]) * mile_scale;
  r.incidents = p.incidents[i];
  r.incidents_by_type[0] = p.incidents[i];
  r.contacts_known = true;
  r.collisions = p.collisions[i];
  r.at_fault_collisions = p.at_fault[i];
  r.has_safety = true;
  r.near_misses = p.near_misses[i];
  r.best_incident_free_miles = r.miles;
  return r;
}

BenchData bench(const std::string& name, std::vector<RunRow> runs) {
  BenchData b;
  b.name = name;
  std::vector<std::string> policies;
  for (const RunRow& r : runs) {
    if (std::find(policies.begin(), policies.end(), r.policy) == policies.end()) {
      policies.push_back(r.policy);
    }
  }
  b.manifest = {{"policies", policies},
                {"minutes", 30.0},
                {"steps_per_call", 0},
                {"map", {{"hash", "calibration"}}},
                {"params_hash", "calibration"}};
  b.runs = std::move(runs);
  return b;
}

GateOutcome gate(int draws, std::uint64_t seed,
                 const std::function<std::pair<BenchData, BenchData>(core::Rng&)>& make,
                 const std::string& watched, int resamples) {
  core::Rng rng(seed);
  GateOutcome out;
  CompareOptions o;
  o.resamples = resamples;
  for (int d = 0; d < draws; ++d) {
    const auto [base, candidate] = make(rng);
    const nlohmann::json r = compare_benches(base, candidate, o);
    ++out.draws;
    if (!r["worse"].empty()) ++out.failed;
    if (!r["withheld"].empty()) ++out.withheld;
    if (watched.empty()) continue;
    for (const auto& c : r["comparisons"]) {
      for (const auto& [metric, f] : c["figures"].items()) {
        const std::string who = c["candidate_policy"].get<std::string>() + " / " +
                                c["traffic"].get<std::string>() + ": " + metric;
        if (who == watched && f.is_object() && f["verdict"] == "better") ++out.better;
      }
    }
  }
  return out;
}

std::function<std::pair<BenchData, BenchData>(core::Rng&)> policy_benches(
    const std::string& set_a, const std::string& set_b, const std::string& policy, std::size_t n,
    bool paired, double add_mph) {
  return [=](core::Rng& rng) {
    std::vector<RunRow> base, candidate;
    for (const char* traffic : {"faithful", "calm"}) {
      const Population& a = population(set_a, policy, traffic);
      const Population& b = population(set_b, policy, traffic);
      const auto ia = draw(rng, a.size(), n);
      const auto ib = paired ? ia : draw(rng, b.size(), n);
      for (std::size_t k = 0; k < n; ++k) {
        // Paired: each seed's two runs go to the arms in a random order, so that the arms
        // are equal in distribution whatever the two populations' own luck.
        const bool swap = paired && (rng.next() & 1U);
        base.push_back(run_row(swap ? b : a, ia[k], k + 1));
        candidate.push_back(run_row(swap ? a : b, ib[k], k + 1, add_mph));
      }
    }
    return std::make_pair(bench("base", std::move(base)), bench("candidate", std::move(candidate)));
  };
}

std::function<std::pair<BenchData, BenchData>(core::Rng&)> thinned_benches(
    const std::string& set, const std::string& policy, std::size_t n, Rate r, double keep) {
  return [=](core::Rng& rng) {
    std::vector<RunRow> base, candidate;
    for (const char* traffic : {"faithful", "calm"}) {
      const Population& p = population(set, policy, traffic);
      const auto ia = draw(rng, p.size(), n);
      const auto ib = draw(rng, p.size(), n);
      for (std::size_t k = 0; k < n; ++k) {
        base.push_back(run_row(p, ia[k], k + 1));
        RunRow c = run_row(p, ib[k], k + 1);
        const auto events = static_cast<int>(counts(p, r)[ib[k]]);
        int kept = 0;
        for (int e = 0; e < events; ++e) kept += rng.uniform01() < keep ? 1 : 0;
        const double removed = events - kept;
        switch (r) {
          case Rate::incidents:
            c.incidents -= removed;
            c.incidents_by_type[0] -= removed;
            break;
          case Rate::collisions:
            c.collisions -= removed;
            c.at_fault_collisions = std::min(c.at_fault_collisions, c.collisions);
            break;
          case Rate::at_fault:
            c.at_fault_collisions -= removed;
            c.collisions -= removed;
            break;
          case Rate::near_misses:
            c.near_misses -= removed;
            break;
        }
        candidate.push_back(c);
      }
    }
    return std::make_pair(bench("base", std::move(base)), bench("candidate", std::move(candidate)));
  };
}

std::function<std::pair<BenchData, BenchData>(core::Rng&)> noisy_benches(std::size_t n, double sd) {
  return [=](core::Rng& rng) {
    std::vector<RunRow> base, candidate;
    for (const auto& [key, p] : rows()) {
      if (p.set != "a30") continue;
      for (std::size_t i = 0; i < n && i < p.size(); ++i) {
        base.push_back(run_row(p, i, p.seed[i], 0.0, 1.0 + sd * normal(rng)));
        candidate.push_back(run_row(p, i, p.seed[i], 0.0, 1.0 + sd * normal(rng)));
      }
    }
    return std::make_pair(bench("base", std::move(base)), bench("candidate", std::move(candidate)));
  };
}

}  // namespace overtake::eval::calibration
