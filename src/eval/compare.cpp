#include "overtake/eval/compare.hpp"

#include <algorithm>
#include <cstdio>
#include <set>
#include <stdexcept>

#include "overtake/eval/stats.hpp"
#include "overtake/eval/summary.hpp"

namespace overtake::eval {
namespace {

using nlohmann::json;

std::vector<std::string> policies_of(const BenchData& b) {
  std::vector<std::string> out;
  if (b.manifest.contains("policies") && b.manifest["policies"].is_array()) {
    for (const json& p : b.manifest["policies"]) {
      if (p.is_string()) out.push_back(p.get<std::string>());
    }
  }
  for (const RunRow& r : b.runs) {
    if (std::find(out.begin(), out.end(), r.policy) == out.end()) out.push_back(r.policy);
  }
  return out;
}

std::vector<std::string> traffic_of(const BenchData& b) {
  std::vector<std::string> out;
  for (const RunRow& r : b.runs) {
    if (std::find(out.begin(), out.end(), r.traffic) == out.end()) out.push_back(r.traffic);
  }
  return out;
}

std::string list(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? "none" : s;
}

/// A manifest value as text for messages ("?" when missing).
std::string manifest_text(const json& m, const json::json_pointer& at) {
  if (!m.contains(at)) return "?";
  return m[at].is_string() ? m[at].get<std::string>() : m[at].dump();
}

bool has_policy(const BenchData& b, const std::string& policy) {
  return std::any_of(b.runs.begin(), b.runs.end(),
                     [&](const RunRow& r) { return r.policy == policy; });
}

std::vector<const RunRow*> runs_of(const BenchData& b, const std::string& policy,
                                   const std::string& traffic) {
  std::vector<const RunRow*> out;
  for (const RunRow& r : b.runs) {
    if (r.policy == policy && r.traffic == traffic) out.push_back(&r);
  }
  return out;
}

std::string pad(std::string s, std::size_t width, bool right = false) {
  if (s.size() >= width) return s;
  const std::string fill(width - s.size(), ' ');
  return right ? fill + s : s + fill;
}

// Refuses two benches whose runs are no pairs (other maps, lengths or steps per call); the
// notes: parameters that differ.
json check_pairable(const BenchData& base, const BenchData& candidate) {
  // Runs are pairs only on the same road, for the same time, with the same latency draws.
  for (const auto& [pointer, what] : std::vector<std::pair<json::json_pointer, std::string>>{
           {json::json_pointer("/map/hash"), "maps"},
           {json::json_pointer("/minutes"), "durations (minutes)"},
           {json::json_pointer("/steps_per_call"), "steps per call"}}) {
    const std::string a = manifest_text(base.manifest, pointer);
    const std::string b = manifest_text(candidate.manifest, pointer);
    if (a != b) {
      throw NotComparable("the benches ran with different " + what + " (" + base.name + ": " + a +
                          ", " + candidate.name + ": " + b + "): their runs are not pairs");
    }
  }
  json notes = json::array();
  const std::string pa = manifest_text(base.manifest, json::json_pointer("/params_hash"));
  const std::string pb = manifest_text(candidate.manifest, json::json_pointer("/params_hash"));
  if (pa != pb) {
    notes.push_back("the parameters differ (hash " + pa + " and " + pb +
                    "): the runs meet the same traffic only if the world's parameters are the "
                    "same (a planner's may differ)");
  }

  return notes;
}

// The policies compared: --pair's, else each policy of both benches with itself.
std::vector<PolicyPair> pairs_of(const BenchData& base, const BenchData& candidate,
                                 const CompareOptions& options) {
  const std::vector<std::string> base_policies = policies_of(base);
  const std::vector<std::string> cand_policies = policies_of(candidate);
  std::vector<PolicyPair> pairs = options.pairs;
  if (pairs.empty()) {
    for (const auto& p : base_policies) {
      if (has_policy(candidate, p) && has_policy(base, p)) pairs.push_back({p, p});
    }
    if (pairs.empty()) {
      throw NotComparable("no policy is in both benches (" + base.name + ": " +
                          list(base_policies) + "; " + candidate.name + ": " + list(cand_policies) +
                          "); pair them with --pair OLD=NEW");
    }
  }
  for (const PolicyPair& p : pairs) {
    if (!has_policy(base, p.base)) {
      throw std::invalid_argument(base.name + " has no runs of policy '" + p.base + "' (it has " +
                                  list(base_policies) + ")");
    }
    if (!has_policy(candidate, p.candidate)) {
      throw std::invalid_argument(candidate.name + " has no runs of policy '" + p.candidate +
                                  "' (it has " + list(cand_policies) + ")");
    }
  }
  return pairs;
}

// The comparisons of each pair on each traffic profile both benches ran (notes added for
// what was not compared).
json comparisons_of(const BenchData& base, const BenchData& candidate,
                    const std::vector<PolicyPair>& pairs, const std::vector<Metric>& metrics,
                    const CompareOptions& options, json& notes) {
  const std::vector<std::string> cand_traffic = traffic_of(candidate);
  json comparisons = json::array();
  for (const PolicyPair& p : pairs) {
    for (const std::string& t : traffic_of(base)) {
      if (std::find(cand_traffic.begin(), cand_traffic.end(), t) == cand_traffic.end()) continue;
      const auto b = runs_of(base, p.base, t);
      const auto c = runs_of(candidate, p.candidate, t);
      if (b.empty() || c.empty()) continue;
      json result = compare_paired(b, c, "compare|" + p.base + "|" + p.candidate + "|" + t, metrics,
                                   options.resamples);
      const auto seeds = result["seeds"].get<std::size_t>();
      if (seeds == 0) {
        notes.push_back(p.base + " / " + t + ": no seed in common, not compared");
        continue;
      }
      if (seeds < std::max(b.size(), c.size())) {
        notes.push_back(p.base + " / " + t + ": " + std::to_string(seeds) + " seeds paired of " +
                        std::to_string(b.size()) + " and " + std::to_string(c.size()));
      }
      for (const Metric m : metrics) {
        const std::string why =
            unavailable_reason(m, b).empty() ? unavailable_reason(m, c) : unavailable_reason(m, b);
        if (!why.empty()) {
          notes.push_back(p.candidate + " / " + t + ": " + std::string(info(m).name) +
                          " not compared: " + why);
        }
      }
      comparisons.push_back({{"base_policy", p.base},
                             {"candidate_policy", p.candidate},
                             {"traffic", t},
                             {"seeds", seeds},
                             {"figures", result["figures"]}});
    }
  }
  if (comparisons.empty()) {
    throw NotComparable("no runs to pair: " + base.name + " and " + candidate.name +
                        " share no traffic profile and seed for the policies compared");
  }
  return comparisons;
}

}  // namespace

json compare_benches(const BenchData& base, const BenchData& candidate,
                     const CompareOptions& options) {
  json notes = check_pairable(base, candidate);
  const std::vector<PolicyPair> pairs = pairs_of(base, candidate, options);
  std::vector<Metric> metrics = options.metrics;
  if (metrics.empty()) metrics.assign(all_metrics().begin(), all_metrics().end());
  json comparisons = comparisons_of(base, candidate, pairs, metrics, options, notes);
  const std::size_t tests = judge_family(comparisons);
  json worse = json::array();
  json withheld = json::array();
  for (const json& c : comparisons) {
    const std::string who =
        c["candidate_policy"].get<std::string>() + " / " + c["traffic"].get<std::string>();
    if (c["seeds"].get<std::size_t>() < kMinSeeds) {
      withheld.push_back(who + ": too few seeds: " + std::to_string(c["seeds"].get<std::size_t>()) +
                         ", need at least " + std::to_string(kMinSeeds));
      continue;
    }
    for (const auto& [name, f] : c["figures"].items()) {
      if (!f.is_null() && f["verdict"] == "worse") worse.push_back(who + ": " + name);
    }
  }
  return {{"base", base.name},          {"candidate", candidate.name},       {"notes", notes},
          {"comparisons", comparisons}, {"verdicts", verdict_method(tests)}, {"worse", worse},
          {"withheld", withheld}};
}

std::string compare_text(const json& result) {
  std::string out = "overtake compare: " + result["base"].get<std::string>() + " (before) -> " +
                    result["candidate"].get<std::string>() + " (after)\n";
  for (const json& n : result["notes"]) out += "  note: " + n.get<std::string>() + "\n";
  for (const json& c : result["comparisons"]) {
    const std::string bp = c["base_policy"], cp = c["candidate_policy"];
    out += "\n" + (bp == cp ? cp : bp + " -> " + cp) + " (" + c["traffic"].get<std::string>() +
           ", " + std::to_string(c["seeds"].get<std::size_t>()) + " seeds paired)\n";
    out += "  " + pad("figure", 32) + pad("before", 9, true) + pad("after", 9, true) + "   " +
           pad("change (95% interval)", 28) + pad("P(improvement)", 20) + "verdict\n";
    for (const Metric m : all_metrics()) {
      const MetricInfo& mi = info(m);
      const std::string name(mi.name);
      if (!c["figures"].contains(name)) continue;
      const json& f = c["figures"][name];
      const std::string label = std::string(mi.label) + " (" + std::string(mi.unit) + ")";
      if (f.is_null()) {
        out += "  " + pad(label, 32) + "not in both benches' rows\n";
        continue;
      }
      constexpr int decimals = 2;
      std::string change = signed_fixed(f["difference"], decimals);
      if (f["ci"].is_array()) {
        change += " (" + signed_fixed(f["ci"][0], decimals) + ", " +
                  signed_fixed(f["ci"][1], decimals) + ")";
      }
      std::string chance = "–";
      if (f["probability_of_improvement"].is_number()) {
        chance = fixed(f["probability_of_improvement"], 2) + " (" +
                 fixed(f["probability_of_improvement_ci"][0], 2) + ", " +
                 fixed(f["probability_of_improvement_ci"][1], 2) + ")";
      }
      out += "  " + pad(label, 32) + pad(fixed(f["base"], decimals), 9, true) +
             pad(fixed(f["candidate"], decimals), 9, true) + "   " + pad(change, 28) +
             pad(chance, 20) + f["verdict"].get<std::string>() + "\n";
    }
  }
  const json& v = result["verdicts"];
  out += "\nVerdicts: " + std::to_string(v["family_tests"].get<std::size_t>()) +
         " tests (a figure the same on every seed is not tested), Holm-corrected to 5% "
         "family-wise (paired t-test for mean speed, exact sign-flip test over seeds for the "
         "rates); no verdict below " +
         std::to_string(v["min_seeds"].get<std::size_t>()) +
         " seeds. Each interval is its figure's own 95%; P(improvement): P(after better than "
         "before) over all pairs of runs.\n";
  for (const json& w : result["withheld"]) out += "  no verdict: " + w.get<std::string>() + "\n";
  const json& worse = result["worse"];
  if (worse.empty()) {
    out += result["withheld"].empty() ? "\nNo figure got significantly worse.\n"
                                      : "\nNo figure judged got significantly worse.\n";
  } else {
    out += "\n" + std::to_string(worse.size()) + " figure" + (worse.size() == 1 ? "" : "s") +
           " significantly worse:\n";
    for (const json& w : worse) out += "  " + w.get<std::string>() + "\n";
  }
  return out;
}

}  // namespace overtake::eval
