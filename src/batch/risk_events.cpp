// `overtake risk`: the events of its base runs cut into scenarios. A base run is a plain run of
// one seed (its copies are branches, which no drive gives again), so the cut is a hunt over
// the seeds of the runs that had an event: each driven again and recorded, its events grouped
// by situation as hunt groups them, each group's first cut into both kinds of scenario and
// driven again to check that it repeats (docs/scenarios.md).

#include <exception>
#include <string>
#include <vector>

#include "overtake/batch/hunt.hpp"
#include "overtake/batch/risk.hpp"
#include "risk_internal.hpp"

namespace overtake::batch::risk_detail {

namespace {

// The hunt's target for the event, or false when the event has no time in a report to cut at.
bool target_of(const RiskEvent& event, HuntSpec& hunt) {
  switch (event.kind) {
    case RiskEventKind::at_fault:
      hunt.target = HuntTarget::at_fault;
      return true;
    case RiskEventKind::contact:
      hunt.target = HuntTarget::collisions;
      return true;
    case RiskEventKind::incident:
      hunt.target = HuntTarget::incidents;
      hunt.incident_type = event.incident;
      return true;
    case RiskEventKind::near_miss:
      return false;
  }
  return false;
}

}  // namespace

void cut_events(const RiskSpec& spec, RiskOutcome& outcome, const std::atomic<bool>* stop) {
  if (spec.scenarios <= 0) return;
  HuntSpec hunt;
  if (!target_of(spec.event, hunt)) {
    outcome.cut_note =
        "near misses are not cut into scenarios: a report counts their episodes, not their times";
    return;
  }
  int events = 0;
  for (const RiskRun& r : outcome.runs) {
    if (r.tally.base_events <= 0 || events >= spec.scenarios) continue;
    hunt.seeds.push_back(r.seed);
    events += r.tally.base_events;
  }
  if (hunt.seeds.empty()) return;
  hunt.policy = spec.policy;
  hunt.planners = spec.planners;
  hunt.maps = {spec.map};
  hunt.traffic = {spec.traffic};
  hunt.minutes = spec.minutes;
  hunt.failures = spec.scenarios;
  hunt.budget_hours = static_cast<double>(hunt.seeds.size()) * spec.minutes / 60.0;
  hunt.config = spec.config;
  hunt.jobs = spec.jobs;
  hunt.out = spec.out / kEventsDir;
  hunt.force = true;  // risk's own folder: a resumed estimate cuts its events again
  try {
    outcome.cut = run_hunt(hunt, stop, {});
    if (outcome.cut->interrupted) outcome.cut_note = "interrupted: the events cut so far are kept";
  } catch (const std::exception& e) {
    outcome.cut_note = std::string("the events could not be cut: ") + e.what();
  }
}

}  // namespace overtake::batch::risk_detail
