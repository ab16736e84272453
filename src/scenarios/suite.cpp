#include "overtake/scenarios/suite.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <sstream>
#include <string_view>
#include <thread>

#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/core/road.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/run/scenario_file.hpp"

namespace overtake::scenarios {

using base::fixed_text;
using run::contact_incident;
namespace {

using nlohmann::json;

std::string incident_text(const sim::Incident& i) {
  std::string text = std::string(sim::to_string(i.type));
  if (i.collision) {
    text += std::string(" ") + std::string(sim::to_string(i.collision->kind));
  }
  return text + " at t " + fixed_text(i.t_s, 2) + " s";
}

}  // namespace

// The incidents of the judged part.
std::vector<sim::Incident> judged_incidents(const sim::Scenario& sc, const sim::RunReport& r,
                                            const ScenarioTrace& trace) {
  const double from = trace.start_s + (sc.cut ? sc.cut->lead_in_s : 0.0) - 1e-9;
  std::vector<sim::Incident> out;
  for (const sim::Incident& i : r.incidents) {
    if (i.t_s >= from) out.push_back(i);
  }
  return out;
}

// The collisions of the judged part, as contacts (one per car touched, however long).
std::vector<sim::Incident> judged_contacts(const sim::Scenario& sc, const sim::RunReport& r,
                                           const ScenarioTrace& trace) {
  const double from = trace.start_s + (sc.cut ? sc.cut->lead_in_s : 0.0) - 1e-9;
  std::vector<sim::Incident> out;
  for (std::size_t k = 0; k < r.contacts.size(); ++k) {
    if (r.contacts[k].t_s >= from)
      out.push_back(contact_incident(r.contacts[k], static_cast<int>(k)));
  }
  return out;
}

std::vector<std::string> judge_scenario(const sim::Scenario& sc, const sim::RunReport& r,
                                        const ScenarioTrace& trace) {
  std::vector<std::string> fails;
  if (r.outcome.end == sim::RunEnd::planner_failed) {
    fails.push_back("the planner failed: " + r.outcome.reason);
  }
  const std::vector<sim::Incident> inc = judged_incidents(sc, r, trace);
  const std::vector<sim::Incident> contacts = judged_contacts(sc, r, trace);
  std::vector<const sim::Incident*> collisions, at_fault;
  for (const sim::Incident& i : contacts) {
    collisions.push_back(&i);
    if (i.collision->at_fault) at_fault.push_back(&i);
  }
  const auto limit = [&](const std::optional<int>& max, std::size_t got, const char* what,
                         const sim::Incident* first) {
    if (max && got > static_cast<std::size_t>(*max)) {
      fails.push_back(std::to_string(got) + " " + what + (got == 1 ? "" : "s") + " (at most " +
                      std::to_string(*max) + "); the first: " + incident_text(*first));
    }
  };
  sim::ScenarioExpect ex = sc.expect;
  if (!ex.any()) ex.max_at_fault_collisions = 0;
  limit(ex.max_at_fault_collisions, at_fault.size(), "at-fault collision",
        at_fault.empty() ? nullptr : at_fault.front());
  limit(ex.max_collisions, collisions.size(), "collision",
        collisions.empty() ? nullptr : collisions.front());
  limit(ex.max_incidents, inc.size(), "incident", inc.empty() ? nullptr : &inc.front());
  if (ex.reach_lane) {
    const auto lane = static_cast<std::size_t>(*ex.reach_lane);
    const auto& reached =
        lane < trace.lane_reached_s.size() ? trace.lane_reached_s[lane] : std::nullopt;
    if (!reached || *reached > ex.reach_lane_by_s + 1e-9) {
      fails.push_back("did not reach lane " + std::to_string(*ex.reach_lane) + " by t " +
                      fixed_text(ex.reach_lane_by_s, 1) + " s" +
                      (reached ? " (reached it at t " + fixed_text(*reached, 2) + " s)"
                               : std::string(" (never)")));
    }
  }
  const double lead_in_s = sc.cut ? sc.cut->lead_in_s : 0.0;
  const double judged_m = judged_distance_m(r, trace);
  if (ex.min_distance_m && judged_m < *ex.min_distance_m) {
    fails.push_back("drove " + fixed_text(judged_m, 1) + " m" +
                    (lead_in_s > 0.0 ? std::string(" after the lead-in") : std::string()) +
                    ", less than " + fixed_text(*ex.min_distance_m, 1) + " m");
  }
  // A run over before its lead-in was has nothing judged: it cannot pass.
  if (lead_in_s > 0.0 && r.duration_s + 1e-9 < lead_in_s &&
      r.outcome.end != sim::RunEnd::planner_failed) {
    fails.push_back("the run lasted " + fixed_text(r.duration_s, 2) + " s, within the lead-in (" +
                    fixed_text(lead_in_s, 2) + " s): nothing was judged");
  }
  return fails;
}

double judged_distance_m(const sim::RunReport& report, const ScenarioTrace& trace) {
  return std::max(0.0, report.distance_m - trace.lead_in_distance_m);
}

}  // namespace overtake::scenarios
