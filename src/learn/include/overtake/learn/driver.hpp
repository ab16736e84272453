#pragma once
// A policy learned on the environment, in a planner's seat (`drive --policy-py`, `bench`,
// `risk`, the protocol): it is told the telemetry as any planner is, decides every
// decision_steps world steps as in the environment, and its decisions are carried out by the
// reference planner's trajectory layer as the environment carries them out. Between two
// decisions the executor plans on with the last targets at every call.

#include <cstdint>
#include <memory>
#include <span>

#include "overtake/core/plan.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/learn/observation.hpp"
#include "overtake/learn/params.hpp"
#include "overtake/learn/vec_env.hpp"
#include "overtake/run/config.hpp"

namespace overtake::planner::reference {
class ReferencePolicy;
}  // namespace overtake::planner::reference

namespace overtake::learn {

class PolicyDriver {
 public:
  /// `kind`: meta or continuous (a path agent gives its paths itself: std::invalid_argument).
  /// `line` and `config` outlive the driver.
  PolicyDriver(const core::ReferenceLine& line, double loop_length_m, const run::Config& config,
               const EnvParams& params, ActionKind kind);
  ~PolicyDriver();
  PolicyDriver(const PolicyDriver&) = delete;
  PolicyDriver& operator=(const PolicyDriver&) = delete;

  /// Whether the agent decides at this call: the first, then each once decision_steps world
  /// steps have gone since its last decision (the points of the sent path the world took).
  [[nodiscard]] bool decision_due(const core::Telemetry& t) const;
  /// The observation now, as the environment would give it (observation_size() floats).
  void observe(const core::Telemetry& t, std::span<float> out) const;
  [[nodiscard]] std::size_t observation_size() const;
  /// This call's path. `meta` or `continuous` (by the kind; null: no decision at this call)
  /// moves the targets first; std::invalid_argument for an action out of its range.
  [[nodiscard]] core::PlanResult plan(const core::Telemetry& t, const std::int64_t* meta,
                                      const float* continuous);
  [[nodiscard]] const EgoContext& targets() const { return ego_; }

 private:
  const run::Config& config_;
  EnvParams params_;
  ActionKind kind_;
  double loop_length_m_;
  std::unique_ptr<planner::reference::ReferencePolicy> executor_;
  EgoContext ego_;
  bool started_ = false;
  std::size_t sent_ = 0;       // points of the last path sent
  long since_steps_ = 0;       // world steps since the last decision (at the last call)
  long since_lane_steps_ = 0;  // ... since the target lane last changed
  double speed_at_decision_mps_ = 0.0;
};

}  // namespace overtake::learn
