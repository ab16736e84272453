// The simulator as a system splitting runs (eval::SplitSystem): one world and one in-process
// policy, saved and restored whole (the run's checkpoint and the policy's state), a copy's
// random draws started afresh from its seed (sim::RunOptions::reseed).

#include "risk_internal.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

#include "overtake/planner/policy.hpp"
#include "overtake/sim/run.hpp"

namespace overtake::batch::risk_detail {

namespace {

constexpr double kMetresPerMile = 1609.344;

// The count of the event the scorecard holds now.
long event_count(const sim::Scorecard& card, const RiskEvent& event) {
  switch (event.kind) {
    case RiskEventKind::at_fault:
      return static_cast<long>(
          std::count_if(card.contacts().begin(), card.contacts().end(),
                        [](const sim::Contact& c) { return c.collision.at_fault; }));
    case RiskEventKind::contact:
      return static_cast<long>(card.contacts().size());
    case RiskEventKind::near_miss:
      return card.safety().summary().near_miss_episodes;
    case RiskEventKind::incident:
      return card.referee().counts()[static_cast<std::size_t>(event.incident)];
  }
  return 0;
}

class WorldBranches final : public eval::SplitSystem {
 public:
  WorldBranches(const RunInputs& in, std::uint64_t seed, const std::atomic<bool>* stop,
                std::vector<RiskFailure>* failures)
      : in_(in), stop_(stop), failures_(failures), seed_(seed) {
    world_ = std::make_unique<sim::World>(in.track->map, in.track->line, in.config.world,
                                          in.profile, seed);
    policy_ = in.entry->make(in.track->line, in.config.planner);
    sim::RunOptions o;
    o.duration_s = in.minutes * 60.0;
    o.seed = seed;
    stepper_ = std::make_unique<sim::Stepper>(*world_, o);
    sync();
  }

  double score() override { return -sim::proximity(*world_, in_.params->score).margin_m; }

  std::size_t save() override {
    saved_[next_] = {stepper_->save(), planner::save_policy_state(*policy_), path_};
    return next_++;
  }

  void restore(std::size_t handle, std::optional<std::uint64_t> reseed) override {
    const Saved& s = saved_.at(handle);
    sim::RunOptions o;
    o.restore = s.run;
    o.restore_scope = sim::RunOptions::RestoreScope::whole_run;
    o.reseed = reseed;
    stepper_.reset();
    stepper_ = std::make_unique<sim::Stepper>(*world_, o);
    // A policy whose state a checkpoint holds takes it back; one that keeps none is made
    // afresh (nothing of the other path's is left in it).
    if (!planner::restore_policy_state(*policy_, s.policy)) {
      policy_ = in_.entry->make(in_.track->line, in_.config.planner);
    }
    sync();
    // A copy is numbered as the splitting numbers it (in the order copies are made, from 1);
    // going back to a saved state goes back to the path that saved it.
    path_ = reseed.has_value() ? ++copies_ : s.path;
  }

  void release(std::size_t handle) override { saved_.erase(handle); }

  eval::SplitStep advance() override {
    if (stop_ && stop_->load(std::memory_order_relaxed)) throw Interrupted{};
    core::PlanResult plan;
    try {
      plan = policy_->plan(stepper_->telemetry());
    } catch (const std::exception& e) {
      // The planner's failure ends this path where it is: what it drove counts, the failure
      // is said, and it is never the event.
      if (failures_) failures_->push_back({path_, world_->time_s(), e.what()});
      eval::SplitStep s;
      s.ended = true;
      s.at = world_->time_s();
      return s;
    }
    stepper_->apply(std::move(plan), 0.0, 0.0);
    stepper_->step_one_call();
    eval::SplitStep s;
    const long count = event_count(stepper_->scorecard(), in_.event);
    const double dist = stepper_->scorecard().referee().distance_m();
    const double t = world_->time_s();
    s.events = static_cast<int>(std::max(0L, count - count_));
    s.exposure = dist - distance_m_;
    s.cost = t - t_s_;
    s.at = t;
    count_ = count;
    distance_m_ = dist;
    t_s_ = t;
    s.ended = stepper_->finished();
    s.score = s.ended ? 0.0 : score();
    return s;
  }

 private:
  struct Saved {
    std::string run;
    std::string policy;
    std::size_t path = 0;  // the path that saved it
  };

  // The running counts from the scorecard and world as they are now.
  void sync() {
    count_ = event_count(stepper_->scorecard(), in_.event);
    distance_m_ = stepper_->scorecard().referee().distance_m();
    t_s_ = world_->time_s();
  }

  const RunInputs& in_;
  const std::atomic<bool>* stop_;
  std::vector<RiskFailure>* failures_;
  std::uint64_t seed_;
  std::unique_ptr<sim::World> world_;
  std::unique_ptr<planner::Policy> policy_;
  std::unique_ptr<sim::Stepper> stepper_;
  std::map<std::size_t, Saved> saved_;
  std::size_t next_ = 0;
  long count_ = 0;
  double distance_m_ = 0.0;
  double t_s_ = 0.0;
  std::size_t path_ = 0;    // the path running now: 0 the base path, else a copy's number
  std::size_t copies_ = 0;  // copies made so far
};

}  // namespace

std::unique_ptr<eval::SplitSystem> make_world_branches(const RunInputs& in, std::uint64_t seed,
                                                       const std::atomic<bool>* stop,
                                                       std::vector<RiskFailure>* failures) {
  return std::make_unique<WorldBranches>(in, seed, stop, failures);
}

std::optional<eval::SplitTally> plain_run(const RunInputs& in, const RiskSpec& spec,
                                          std::size_t index, std::uint64_t seed,
                                          const std::atomic<bool>* stop,
                                          std::optional<RiskFailure>& failure) {
  run::DriveOptions o;
  o.policy = spec.policy;
  o.planners = spec.planners;
  o.traffic = spec.traffic;
  o.seed = seed;
  o.minutes = spec.minutes;
  o.map = spec.map;
  o.planner_log = spec.out / "logs" / ("run" + std::to_string(index) + ".log");
  std::error_code ec;
  std::filesystem::create_directories(spec.out / "logs", ec);
  const run::DriveResult r = run::drive_on(*in.track, in.config, o, {}, stop);
  const sim::RunReport& rep = r.report;
  if (rep.outcome.end == sim::RunEnd::stopped) return std::nullopt;
  failure.reset();
  if (rep.outcome.end == sim::RunEnd::planner_failed) {
    // What it drove until then counts; the failure is the planner's, not the event.
    failure = RiskFailure{0, rep.outcome.t_s, rep.outcome.reason};
  }
  long events = 0;
  switch (in.event.kind) {
    case RiskEventKind::at_fault:
      events = static_cast<long>(
          std::count_if(rep.contacts.begin(), rep.contacts.end(),
                        [](const sim::Contact& c) { return c.collision.at_fault; }));
      break;
    case RiskEventKind::contact:
      events = static_cast<long>(rep.contacts.size());
      break;
    case RiskEventKind::near_miss:
      events = rep.safety.near_miss_episodes;
      break;
    case RiskEventKind::incident:
      events = rep.incident_counts[static_cast<std::size_t>(in.event.incident)];
      break;
  }
  eval::SplitTally t;
  t.weighted_events = static_cast<double>(events);
  t.base_events = static_cast<int>(events);
  t.exposure = rep.distance_m;
  t.cost = rep.duration_s;
  t.base_cost = rep.duration_s;
  for (const sim::Contact& c : rep.contacts) {
    const bool counted = in.event.kind == RiskEventKind::contact ||
                         (in.event.kind == RiskEventKind::at_fault && c.collision.at_fault);
    if (counted) t.events.push_back({1.0, 0, 0, c.t_s, c.t_s});
  }
  return t;
}

double miles_of(double metres) {
  return metres / kMetresPerMile;
}

}  // namespace overtake::batch::risk_detail
