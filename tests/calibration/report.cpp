// Prints the calibration of docs/evaluation.md in full: every shape's coverage at 8 and 20
// seeds, the gate's false alarms, the power against real changes, and how many seeds a change
// needs. `overtake_stats_calibration [DRAWS]` (default 1000; the tests use the same draws).

#include <cstdio>
#include <string>
#include <vector>

#include "calibration.hpp"

using namespace overtake::eval::calibration;

int main(int argc, char** argv) {
  const int draws = argc > 1 ? std::stoi(argv[1]) : 1000;
  const std::vector<std::string> policies = {"reference", "walkthrough", "seed000", "seed001",
                                             "seed002",   "seed003",     "seed004"};
  std::printf("Coverage (%d draws of n seeds each, with replacement from 100)\n\n", draws);
  std::printf("| runs | policy | traffic | speed n=8 | n=20 | incidents n=8 | n=20 | collisions "
              "n=8 | n=20 | at fault n=8 | n=20 | near misses n=8 | n=20 |\n");
  std::printf("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const char* set : {"a30", "a10"}) {
    for (const auto& p : policies) {
      for (const char* t : {"faithful", "calm"}) {
        const Population& pop = population(set, p, t);
        std::printf("| %s | %s | %s", set[1] == '3' ? "30 min" : "10 min", p.c_str(), t);
        for (const std::size_t n : {8U, 20U}) {
          std::printf(" | %.3f", speed_coverage(pop, n, draws, 101 + n, 2000));
        }
        for (const Rate r : kRates) {
          for (const std::size_t n : {8U, 20U}) {
            if (true_rate(pop, r) == 0.0) {
              std::printf(" | –");
            } else {
              std::printf(" | %.3f%s", rate_coverage(pop, r, n, draws, 201 + n),
                          dispersion(pop, r) > 20.0 ? "*" : "");
            }
          }
        }
        std::printf(" |\n");
      }
    }
  }
  std::printf("\nPaired speed differences, reference - other (and twins)\n\n");
  for (const char* set : {"a30", "a10"}) {
    for (const char* t : {"faithful", "calm"}) {
      for (std::size_t k = 1; k < policies.size(); ++k) {
        const Population& a = population(set, "reference", t);
        const Population& b = population(set, policies[k], t);
        std::printf("%s %s reference - %s: n=8 %.3f n=20 %.3f\n", set, t, policies[k].c_str(),
                    speed_difference_coverage(a, b, 8, draws, 309, 1000),
                    speed_difference_coverage(a, b, 20, draws, 321, 1000));
      }
    }
  }
  for (const char* p : {"reference", "seed004"}) {
    for (const char* t : {"faithful", "calm"}) {
      const Population& a = population("a30", p, t);
      const Population& b = population("b30", p, t);
      std::printf("twins %s %s: n=8 %.3f n=20 %.3f\n", p, t,
                  speed_difference_coverage(a, b, 8, draws, 309, 1000),
                  speed_difference_coverage(a, b, 20, draws, 321, 1000));
    }
  }
  std::printf("\nPaired rate differences (all pairs of policies, 30 min): least coverage\n\n");
  for (const Rate r : kRates) {
    for (const std::size_t n : {8U, 20U}) {
      double least = 1.0;
      std::string at;
      for (const char* t : {"faithful", "calm"}) {
        for (std::size_t i = 0; i < policies.size(); ++i) {
          for (std::size_t j = i + 1; j < policies.size(); ++j) {
            const Population& a = population("a30", policies[i], t);
            const Population& b = population("a30", policies[j], t);
            if (dispersion(a, r) > 20.0 || dispersion(b, r) > 20.0) continue;
            if (true_rate(a, r) == 0.0 && true_rate(b, r) == 0.0) continue;
            const double c = rate_difference_coverage(a, b, r, n, draws, 401 + n);
            if (c < least) {
              least = c;
              at = policies[i] + " - " + policies[j] + " " + t;
            }
          }
        }
      }
      std::printf("%s n=%zu: %.3f (%s)\n", name(r), n, least, at.c_str());
    }
  }
  std::printf("\nThe gate on benches equal in distribution (failures of --fail-if-worse)\n\n");
  for (const auto& p : policies) {
    const GateOutcome g = gate(draws, 501, policy_benches("a30", "a30", p, 20, false));
    std::printf("independent seeds, %s, 20 seeds: %d of %d (%.1f%%)\n", p.c_str(), g.failed,
                g.draws, 100.0 * g.failure_rate());
  }
  for (const char* p : {"reference", "seed004"}) {
    for (const std::size_t n : {8U, 20U}) {
      const GateOutcome g = gate(draws, 502, policy_benches("a30", "b30", p, n, true));
      std::printf("twins, %s, %zu seeds: %d of %d (%.1f%%)\n", p, n, g.failed, g.draws,
                  100.0 * g.failure_rate());
    }
  }
  const GateOutcome noisy = gate(draws, 601, noisy_benches(20, 0.04));
  std::printf("7 policies x 2 profiles, 20 seeds, 4%% noise: %d of %d (%.1f%%)\n", noisy.failed,
              noisy.draws, 100.0 * noisy.failure_rate());
  std::printf("\nPower: the reference planner's twin faster by D mph, found better (share)\n\n");
  for (const double mph : {0.5, 1.0, 2.0}) {
    for (const std::size_t n : {8U, 20U, 30U, 50U, 80U}) {
      const GateOutcome f = gate(draws / 2, 700 + n, policy_benches("a30", "b30", "reference", n,
                                                                   true, mph),
                                 "reference / faithful: mean_speed_mph");
      const GateOutcome c = gate(draws / 2, 800 + n, policy_benches("a30", "b30", "reference", n,
                                                                   true, mph),
                                 "reference / calm: mean_speed_mph");
      std::printf("+%.1f mph, %zu seeds: faithful %.2f, calm %.2f\n", mph, n, f.better_rate(),
                  c.better_rate());
    }
  }
  return 0;
}
