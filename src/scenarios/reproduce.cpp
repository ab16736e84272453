#include "overtake/scenarios/reproduce.hpp"

#include <cmath>
#include <span>

#include "overtake/base/text.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/run/scenario_file.hpp"

namespace overtake::scenarios {

using base::fixed_text;
using run::Config;
using run::drive_on;
using run::DriveOptions;
using run::DriveResult;
using run::load_scenario;
using run::Track;
namespace {

/// Two times at the same world step (steps are 0.02 s; times are the step times).
constexpr double kSameStepS = 0.005;

bool same_incident(const sim::Incident& a, const sim::Incident& b) {
  if (a.type != b.type || std::abs(a.t_s - b.t_s) > kSameStepS) return false;
  if (a.collision.has_value() != b.collision.has_value()) return false;
  return !a.collision || a.collision->kind == b.collision->kind;
}

std::string incident_text(const sim::Incident& i) {
  std::string text(sim::to_string(i.type));
  if (i.collision) text += " " + std::string(sim::to_string(i.collision->kind));
  return text + " at t " + fixed_text(i.t_s, 2) + " s";
}

/// What the drive booked nearest the failure's moment, for a "no".
std::string instead(const sim::RunReport& r, const FailureMark& f) {
  const sim::Incident* near = nullptr;
  for (const sim::Incident& i : r.incidents) {
    if (f.incident && i.type != f.incident->type) continue;
    if (!near || std::abs(i.t_s - f.t_s) < std::abs(near->t_s - f.t_s)) near = &i;
  }
  if (r.outcome.end == sim::RunEnd::planner_failed) {
    return "the planner failed at t " + fixed_text(r.outcome.t_s, 2) + " s";
  }
  if (near) return "a " + incident_text(*near) + " instead";
  return f.incident ? "no " + std::string(sim::to_string(f.incident->type)) + " in the scenario"
                    : "the planner did not fail";
}

/// Keeps the digest of every answer of a drive, with the time it was told at.
class AnswerLog final : public sim::RunObserver {
 public:
  AnswerLog(std::vector<std::pair<double, std::uint64_t>>& out, double step_s)
      : out_(out), step_s_(step_s) {}
  void on_frame(const sim::Frame& frame, std::span<const sim::Incident> /*new*/) override {
    t_s_ = static_cast<double>(frame.step) * step_s_;
  }
  void on_path(std::span<const core::Vec2> path) override {
    out_.emplace_back(t_s_, sim::answer_digest(path));
  }

 private:
  std::vector<std::pair<double, std::uint64_t>>& out_;
  double step_s_;
  double t_s_ = 0.0;
};

}  // namespace

ReproCheck check_reproduction(const Track& track, const Config& config, DriveOptions base,
                              const std::filesystem::path& scenario, const FailureMark& failure,
                              const std::atomic<bool>* stop) {
  ReproCheck check;
  const sim::Scenario sc = load_scenario(scenario, config.road);
  base.scenario = scenario;
  base.record.reset();
  base.live.reset();
  if (sc.duration_s) base.minutes = *sc.duration_s / 60.0;
  AnswerLog log(check.answers, config.world.step_s);
  base.watcher = &log;
  const DriveResult d = drive_on(track, config, base, {}, stop, &sc);
  check.report = d.report;
  if (d.report.outcome.end == sim::RunEnd::stopped) {
    check.stopped = true;
    check.text = "not checked (stopped)";
    return check;
  }
  if (failure.incident) {
    for (const sim::Incident& i : d.report.incidents) {
      if (same_incident(i, *failure.incident)) check.reproduced = true;
    }
  } else {
    check.reproduced = d.report.outcome.end == sim::RunEnd::planner_failed &&
                       std::abs(d.report.outcome.t_s - failure.t_s) <= kSameStepS;
  }
  check.text = check.reproduced ? "yes" : "no: " + instead(d.report, failure);
  if (d.report.warm_up) {
    const sim::WarmUpResult& w = *d.report.warm_up;
    check.text += w.in_step ? " (in step after " + std::to_string(w.in_step_after) + " of " +
                                  std::to_string(w.cycles) + " warm-up cycles)"
                            : " (not in step after " + std::to_string(w.cycles) +
                                  " warm-up cycles: reproduction not guaranteed)";
  }
  return check;
}

std::string drives_differ(const ReproCheck& x, const ReproCheck& y) {
  const sim::RunReport& a = x.report;
  const sim::RunReport& b = y.report;
  if (a.warm_up && b.warm_up) {
    const long k = sim::first_disagreement(*a.warm_up, *b.warm_up);
    if (k >= 0) {
      return "told the same twice, it answered differently at warm-up cycle " +
             std::to_string(k + 1);
    }
  }
  // Up to the first answer that differs, both drives were told the same.
  for (std::size_t k = 0; k < std::min(x.answers.size(), y.answers.size()); ++k) {
    if (x.answers[k] != y.answers[k]) {
      return "told the same twice, it answered differently at cycle " + std::to_string(k + 1) +
             " of the scenario (t " + fixed_text(x.answers[k].first, 2) + " s)";
    }
  }
  const std::size_t n = std::min(a.incidents.size(), b.incidents.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (!same_incident(a.incidents[i], b.incidents[i])) {
      return "told the same twice, it drove differently: a " + incident_text(a.incidents[i]) +
             " one time, a " + incident_text(b.incidents[i]) + " the other";
    }
  }
  if (a.incidents.size() != b.incidents.size()) {
    return "told the same twice, it drove differently: " + std::to_string(a.incidents.size()) +
           " incidents one time, " + std::to_string(b.incidents.size()) + " the other";
  }
  if (a.outcome.end != b.outcome.end || std::abs(a.distance_m - b.distance_m) > 1e-6) {
    return "told the same twice, it drove differently: " + fixed_text(a.distance_m, 2) +
           " m one time, " + fixed_text(b.distance_m, 2) + " m the other";
  }
  return {};
}

}  // namespace overtake::scenarios
