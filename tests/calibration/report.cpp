// Prints the calibration of docs/evaluation.md in full: every shape's coverage at 8 and 20
// seeds, the gate's false alarms, the power against real changes, and how many seeds a change
// needs. `overtake_stats_calibration [DRAWS]` (default 1000; the tests use the same draws).

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "calibration.hpp"

using namespace overtake::eval::calibration;

int main(int argc, char** argv) {
  const int draws = argc > 1 ? std::stoi(argv[1]) : 1000;
  const std::vector<std::string> policies = {"reference", "walkthrough", "seed000", "seed001",
                                             "seed002",   "seed003",     "seed004"};
  // The least coverage of each interval over its shapes, and how many shapes it had.
  struct Least {
    double at8 = 1.0, at20 = 1.0;
    int shapes = 0;
  };
  std::map<std::string, Least> least;
  const auto note = [&](const std::string& what, double c8, double c20) {
    Least& l = least[what];
    l.at8 = std::min(l.at8, c8);
    l.at20 = std::min(l.at20, c20);
    ++l.shapes;
  };
  std::printf("Coverage (%d draws of n seeds each, with replacement from 100)\n\n", draws);
  std::printf(
      "| runs | policy | traffic | speed n=8 | n=20 | incidents n=8 | n=20 | collisions "
      "n=8 | n=20 | at fault n=8 | n=20 | near misses n=8 | n=20 |\n");
  std::printf("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const char* set : {"a30", "a10"}) {
    for (const auto& p : policies) {
      for (const char* t : {"faithful", "calm"}) {
        const Population& pop = population(set, p, t);
        std::printf("| %s | %s | %s", set[1] == '3' ? "30 min" : "10 min", p.c_str(), t);
        const double s8 = speed_coverage(pop, 8, draws, 109, 2000);
        const double s20 = speed_coverage(pop, 20, draws, 121, 2000);
        std::printf(" | %.3f | %.3f", s8, s20);
        note("mean speed", s8, s20);
        for (const Rate r : kRates) {
          if (true_rate(pop, r) == 0.0) {
            std::printf(" | – | –");
            continue;
          }
          const double c8 = rate_coverage(pop, r, 8, draws, 209);
          const double c20 = rate_coverage(pop, r, 20, draws, 221);
          const bool burst = dispersion(pop, r) > 20.0;
          std::printf(" | %.3f%s | %.3f%s", c8, burst ? "*" : "", c20, burst ? "*" : "");
          if (!burst) note(name(r), c8, c20);
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
        const double c8 = speed_difference_coverage(a, b, 8, draws, 309, 1000);
        const double c20 = speed_difference_coverage(a, b, 20, draws, 321, 1000);
        std::printf("%s %s reference - %s: n=8 %.3f n=20 %.3f\n", set, t, policies[k].c_str(), c8,
                    c20);
        note("paired speed difference", c8, c20);
      }
    }
  }
  for (const char* p : {"reference", "seed004"}) {
    for (const char* t : {"faithful", "calm"}) {
      const Population& a = population("a30", p, t);
      const Population& b = population("b30", p, t);
      const double c8 = speed_difference_coverage(a, b, 8, draws, 309, 1000);
      const double c20 = speed_difference_coverage(a, b, 20, draws, 321, 1000);
      std::printf("twins %s %s: n=8 %.3f n=20 %.3f\n", p, t, c8, c20);
      note("paired speed difference", c8, c20);
    }
  }
  std::printf("\nPaired rate differences (all pairs of policies, 30 min)\n\n");
  for (const Rate r : kRates) {
    for (const char* t : {"faithful", "calm"}) {
      for (std::size_t i = 0; i < policies.size(); ++i) {
        for (std::size_t j = i + 1; j < policies.size(); ++j) {
          const Population& a = population("a30", policies[i], t);
          const Population& b = population("a30", policies[j], t);
          if (dispersion(a, r) > 20.0 || dispersion(b, r) > 20.0) continue;
          if (true_rate(a, r) == 0.0 && true_rate(b, r) == 0.0) continue;
          const double c8 = rate_difference_coverage(a, b, r, 8, draws, 409);
          const double c20 = rate_difference_coverage(a, b, r, 20, draws, 421);
          if (c8 < 0.95 || c20 < 0.95) {
            std::printf("%s %s - %s %s: n=8 %.3f n=20 %.3f\n", name(r), policies[i].c_str(),
                        policies[j].c_str(), t, c8, c20);
          }
          note(std::string("paired ") + name(r) + " difference", c8, c20);
        }
      }
    }
  }
  std::printf("\nLeast coverage of each interval (shapes)\n\n");
  for (const auto& [what, l] : least) {
    std::printf("%s: n=8 %.3f, n=20 %.3f (%d shapes)\n", what.c_str(), l.at8, l.at20, l.shapes);
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
  // How many seeds: the least n (of a grid) at which the gate finds a change 80% of the time.
  const std::vector<std::size_t> grid = {8, 12, 16, 20, 25, 30, 40, 50, 60, 80, 100, 120, 160, 200};
  const auto seeds_for = [&](auto make, const std::string& watched) -> std::string {
    for (const std::size_t n : grid) {
      const GateOutcome g = gate(draws / 4, 900 + n, make(n), watched);
      if (g.better_rate() >= 0.8) return std::to_string(n);
    }
    return "> 200";
  };
  std::printf("\nSeeds (each both profiles) for the gate to find a change 80%% of the time\n\n");
  for (const char* traffic : {"faithful", "calm"}) {
    for (const double mph : {0.25, 0.5, 1.0, 2.0}) {
      const std::string watched = std::string("reference / ") + traffic + ": mean_speed_mph";
      std::printf("reference, %s, +%.2f mph: %s seeds\n", traffic, mph,
                  seeds_for(
                      [&](std::size_t n) {
                        return policy_benches("a30", "b30", "reference", n, true, mph);
                      },
                      watched)
                      .c_str());
    }
  }
  for (const char* policy : {"walkthrough", "seed001", "seed003", "seed004"}) {
    const std::string watched = std::string(policy) + " / faithful: at_fault_collisions_per_100mi";
    std::printf(
        "%s, faithful, at-fault collisions halved (%.2f -> %.2f per 100 mi): %s seeds\n", policy,
        true_rate(population("a30", policy, "faithful"), Rate::at_fault),
        0.5 * true_rate(population("a30", policy, "faithful"), Rate::at_fault),
        seeds_for(
            [&](std::size_t n) { return thinned_benches("a30", policy, n, Rate::at_fault, 0.5); },
            watched)
            .c_str());
  }

  std::printf("\nPower: the reference planner's twin faster by D mph, found better (share)\n\n");
  for (const double mph : {0.5, 1.0, 2.0}) {
    for (const std::size_t n : {8U, 20U, 30U, 50U, 80U}) {
      const GateOutcome f =
          gate(draws / 2, 700 + n, policy_benches("a30", "b30", "reference", n, true, mph),
               "reference / faithful: mean_speed_mph");
      const GateOutcome c =
          gate(draws / 2, 800 + n, policy_benches("a30", "b30", "reference", n, true, mph),
               "reference / calm: mean_speed_mph");
      std::printf("+%.1f mph, %zu seeds: faithful %.2f, calm %.2f\n", mph, n, f.better_rate(),
                  c.better_rate());
    }
  }
  return 0;
}
