// The learning environment: its observation's layout, determinism, N worlds against N single
// ones, next-step autoreset, what the meta-actions do, bad actions, and its parameters.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "overtake/learn/observation.hpp"
#include "overtake/learn/params.hpp"
#include "overtake/learn/vec_env.hpp"
#include "overtake/run/config.hpp"
#include "temp_dir.hpp"

namespace overtake::learn {
namespace {

using ::testing::HasSubstr;

// What one call gave, for every env.
struct Step {
  std::vector<float> obs, reward;
  std::vector<std::uint8_t> terminated, truncated;
};

Step step_meta(VecEnv& env, const std::vector<std::int64_t>& actions) {
  Step s;
  const std::size_t n = env.num_envs();
  s.obs.resize(n * env.observation_size());
  s.reward.resize(n);
  s.terminated.resize(n);
  s.truncated.resize(n);
  Actions a;
  a.meta = actions.data();
  env.step(a, {s.obs.data(), s.reward.data(), s.terminated.data(), s.truncated.data()});
  return s;
}

std::vector<float> reset(VecEnv& env, std::optional<std::uint64_t> seed = std::nullopt) {
  std::vector<float> obs(env.num_envs() * env.observation_size());
  env.reset(seed, obs.data());
  return obs;
}

VecEnvSpec spec_of(std::size_t n, std::uint64_t seed, double minutes = 1.0, int threads = 1) {
  VecEnvSpec s;
  s.num_envs = n;
  s.seed = seed;
  s.minutes = minutes;
  s.threads = threads;
  return s;
}

// A few meta-actions that change lanes and speeds, the same for a given env and call.
std::int64_t scripted_action(std::size_t env, int call) {
  const int k = (call / 25 + static_cast<int>(env)) % 7;
  return k < 3 ? MetaAction::keep : k - 2;  // keep, keep, keep, left, right, faster, slower
}

TEST(LearnObservation, NamesTheNearestCarAheadAndBehindInEachLane) {
  core::Telemetry t;
  t.ego.s_m = 5.0;  // near the loop's start: the cars behind are across it
  t.ego.d_m = 6.5;  // the middle lane, 0.5 m right of its centre
  t.ego.speed_mps = 20.0;
  const auto car = [](int id, double s, double d, double vx) {
    core::CarObservation c;
    c.id = id;
    c.s_m = s;
    c.d_m = d;
    c.velocity_mps = {vx, 0.0};
    return c;
  };
  t.cars = {car(1, 35.0, 6.0, 15.0),     // middle lane, ahead: gap 30 - 4.7
            car(2, 55.0, 6.0, 25.0),     // farther in the same slot: not the nearest
            car(3, 985.0, 2.0, 22.0),    // left lane, behind: gap 20 - 4.7
            car(4, 990.0, 10.0, 20.0),   // right lane, behind: gap 15 - 4.7
            car(5, 305.0, 10.0, 20.0)};  // out of range
  EgoContext ego;
  ego.target_lane = 2;
  ego.target_speed_mps = 22.352;
  ego.accel_mps2 = 5.0;
  ego.manoeuvre_s = 2.5;
  ObservationParams p;
  std::vector<float> out(observation_size(3));
  observe(t, ego, core::RoadParams{}, 1000.0, 4.7, p, out);
  ASSERT_EQ(out.size(), 31u);
  EXPECT_FLOAT_EQ(out[0], static_cast<float>(20.0 / 22.352));
  EXPECT_FLOAT_EQ(out[1], 0.25F);  // 0.5 m of a 2 m half lane
  EXPECT_FLOAT_EQ(out[2], 0.5F);
  EXPECT_FLOAT_EQ(out[3], 0.5F);
  EXPECT_FLOAT_EQ(out[4], 0.25F);
  EXPECT_FLOAT_EQ(out[5], 1.0F);
  EXPECT_FLOAT_EQ(out[6], 1.0F);  // the target lane is right of this one
  const auto slot = [&](int lane, bool ahead) {
    return std::vector<float>(out.begin() + 7 + (lane * 2 + (ahead ? 0 : 1)) * 4,
                              out.begin() + 7 + (lane * 2 + (ahead ? 0 : 1)) * 4 + 4);
  };
  EXPECT_THAT(slot(1, true), ::testing::ElementsAre(1.0F, ::testing::FloatEq(0.253F),
                                                    ::testing::FloatEq(-5.0F / 22.352F),
                                                    ::testing::FloatEq(0.0F)));
  EXPECT_THAT(slot(0, false),
              ::testing::ElementsAre(1.0F, ::testing::FloatEq(0.153F),
                                     ::testing::FloatEq(2.0F / 22.352F), ::testing::FloatEq(0.0F)));
  EXPECT_THAT(slot(2, false),
              ::testing::ElementsAre(1.0F, ::testing::FloatEq(0.103F), ::testing::FloatEq(0.0F),
                                     ::testing::FloatEq(0.0F)));
  EXPECT_THAT(slot(0, true), ::testing::Each(0.0F));
  EXPECT_THAT(slot(1, false), ::testing::Each(0.0F));
  EXPECT_THAT(slot(2, true), ::testing::Each(0.0F));  // car 5 is beyond the range
}

TEST(LearnVecEnv, TheSameSeedsAndActionsGiveTheSameArraysByteForByte) {
  VecEnv a(spec_of(3, 11, 1.0, 1));
  VecEnv b(spec_of(3, 11, 1.0, 2));  // other threads: the same arrays
  EXPECT_EQ(reset(a), reset(b));
  for (int call = 0; call < 120; ++call) {
    std::vector<std::int64_t> act(3);
    for (std::size_t i = 0; i < 3; ++i) act[i] = scripted_action(i, call);
    const Step x = step_meta(a, act);
    const Step y = step_meta(b, act);
    ASSERT_EQ(std::memcmp(x.obs.data(), y.obs.data(), x.obs.size() * sizeof(float)), 0) << call;
    ASSERT_EQ(x.reward, y.reward) << call;
    ASSERT_EQ(x.terminated, y.terminated);
    ASSERT_EQ(x.truncated, y.truncated);
  }
}

TEST(LearnVecEnv, NWorldsInOneAreNWorldsAlone) {
  constexpr std::size_t kN = 4;
  VecEnv many(spec_of(kN, 20, 0.5, 2));
  std::vector<std::unique_ptr<VecEnv>> alone;
  for (std::size_t i = 0; i < kN; ++i)
    alone.push_back(std::make_unique<VecEnv>(spec_of(1, 20 + i, 0.5)));
  const std::vector<float> obs = reset(many);
  const std::size_t m = many.observation_size();
  for (std::size_t i = 0; i < kN; ++i) {
    EXPECT_EQ(std::vector<float>(obs.begin() + i * m, obs.begin() + (i + 1) * m), reset(*alone[i]));
  }
  for (int call = 0; call < 200; ++call) {  // past the end of the first episodes (150 calls)
    std::vector<std::int64_t> act(kN);
    for (std::size_t i = 0; i < kN; ++i) act[i] = scripted_action(i, call);
    const Step x = step_meta(many, act);
    for (std::size_t i = 0; i < kN; ++i) {
      const Step y = step_meta(*alone[i], {act[i]});
      ASSERT_EQ(std::vector<float>(x.obs.begin() + i * m, x.obs.begin() + (i + 1) * m), y.obs)
          << "env " << i << " call " << call;
      ASSERT_EQ(x.reward[i], y.reward[0]);
      ASSERT_EQ(x.truncated[i], y.truncated[0]);
    }
  }
}

TEST(LearnVecEnv, AnEpisodeEndsTruncatedAndTheNextCallBeginsTheNextOne) {
  VecEnv env(spec_of(2, 5, 0.1));  // 6 s: 30 decisions of 0.2 s
  (void)reset(env);
  EXPECT_EQ(env.status(0).episode, 1);
  EXPECT_TRUE(env.last_report(0).is_null());
  Step s;
  for (int call = 1; call <= 30; ++call) {
    s = step_meta(env, {MetaAction::keep, MetaAction::keep});
    if (call < 30) {
      ASSERT_EQ(s.truncated[0], 0) << call;
    }
  }
  EXPECT_EQ(s.truncated[0], 1);
  EXPECT_EQ(s.terminated[0], 0);
  EXPECT_NEAR(env.status(0).time_s, 6.0, 1e-9);
  const nlohmann::json report = env.last_report(0);
  ASSERT_TRUE(report.is_object());
  EXPECT_EQ(report["config"]["policy"], "agent");
  EXPECT_EQ(report["config"]["seed"], 5);
  EXPECT_EQ(report["end"], "completed");
  EXPECT_NEAR(report["distance_miles"].get<double>() * 1609.344, env.status(0).distance_m, 0.01);
  // The next call begins episode 2 from its own seed: reward 0, not done, the action not taken.
  const Step next = step_meta(env, {MetaAction::left, MetaAction::keep});
  EXPECT_EQ(next.reward[0], 0.0F);
  EXPECT_EQ(next.truncated[0], 0);
  EXPECT_TRUE(env.status(0).was_reset);
  EXPECT_EQ(env.status(0).episode, 2);
  EXPECT_EQ(env.status(0).episode_seed, 5 + (std::uint64_t{1} << 32));
  EXPECT_EQ(env.status(0).episode_length, 0);
  VecEnv fresh(spec_of(1, 5 + (std::uint64_t{1} << 32), 0.1));
  const std::size_t m = env.observation_size();
  EXPECT_EQ(std::vector<float>(next.obs.begin(), next.obs.begin() + m), reset(fresh));
  // reset(seed) starts every env's episodes again from seed + i.
  const std::vector<float> again = reset(env, 5);
  EXPECT_EQ(std::vector<float>(again.begin(), again.begin() + m), reset(fresh, 5));
  EXPECT_EQ(env.status(1).episode_seed, 6u);
}

TEST(LearnVecEnv, KeepingTheLaneDrivesAndTheMetaActionsChangeLaneAndSpeed) {
  VecEnv env(spec_of(1, 3, 2.0));
  (void)reset(env);
  for (int call = 0; call < 150; ++call) (void)step_meta(env, {MetaAction::keep});  // 30 s
  const EnvStatus kept = env.status(0);
  EXPECT_EQ(kept.collisions, 0u);
  EXPECT_GT(kept.distance_m / kept.time_s, 12.0);  // it drives
  const int lane = kept.lane;
  const std::int64_t change = lane == 0 ? MetaAction::right : MetaAction::left;
  (void)step_meta(env, {change});
  int changed_at = -1;
  for (int call = 0; call < 150 && changed_at < 0; ++call) {
    if (env.status(0).lane != lane) changed_at = call;
    (void)step_meta(env, {MetaAction::keep});
    if (env.status(0).target_lane == lane) (void)step_meta(env, {change});  // refused: again
  }
  EXPECT_GE(changed_at, 0) << "no lane change in 30 s of asking";
  for (int k = 0; k < 8; ++k) (void)step_meta(env, {MetaAction::slower});
  EXPECT_NEAR(env.status(0).target_speed_mps, env.cruise_speed_mps() - 8 * 2.2352, 1e-9);
  for (int call = 0; call < 100; ++call) (void)step_meta(env, {MetaAction::keep});
  EXPECT_LT(env.status(0).speed_mps, env.cruise_speed_mps() - 8 * 2.2352 + 1.0);
  EXPECT_EQ(env.status(0).incidents, 0u) << env.report(0).dump();
}

TEST(LearnVecEnv, BadActionsAreRefusedNamingTheEnvBeforeAnyWorldSteps) {
  VecEnv env(spec_of(2, 1));
  EXPECT_THROW((void)step_meta(env, {0, 0}), std::logic_error);  // before reset
  (void)reset(env);
  try {
    (void)step_meta(env, {0, 5});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("env 1 is 5"));
  }
  EXPECT_EQ(env.status(0).episode_length, 0);  // env 0 did not step either
  EXPECT_THROW((void)step_meta(env, {-1, 0}), std::invalid_argument);

  VecEnvSpec c = spec_of(1, 1);
  c.actions = ActionKind::continuous;
  VecEnv cont(c);
  std::vector<float> obs(cont.observation_size()), r(1);
  std::vector<std::uint8_t> te(1), tr(1);
  cont.reset(std::nullopt, obs.data());
  for (const std::vector<float>& bad :
       std::vector<std::vector<float>>{{1.5F, 0.0F}, {0.5F, -1.1F}, {std::nanf(""), 0.0F}}) {
    Actions a;
    a.continuous = bad.data();
    EXPECT_THROW(cont.step(a, {obs.data(), r.data(), te.data(), tr.data()}), std::invalid_argument);
  }
  VecEnvSpec p = spec_of(1, 1);
  p.actions = ActionKind::path;
  VecEnv path(p);
  path.reset(std::nullopt, obs.data());
  const std::vector<double> half_nan = {1.0, 2.0, std::nan(""), 3.0};
  Actions a;
  a.path = half_nan.data();
  a.path_points = 2;
  try {
    path.step(a, {obs.data(), r.data(), te.data(), tr.data()});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("point 1 not finite"));
  }
}

TEST(LearnVecEnv, ARawPathDrivesTheWorldAsAReplyDoes) {
  VecEnvSpec p = spec_of(1, 2, 0.2);
  p.actions = ActionKind::path;
  VecEnv env(p);
  std::vector<float> obs(env.observation_size()), r(1);
  std::vector<std::uint8_t> te(1), tr(1);
  env.reset(std::nullopt, obs.data());
  // An empty path (a first row of NaN): the ego has nothing queued and stands.
  const std::vector<double> none = {std::nan(""), std::nan("")};
  Actions a;
  a.path = none.data();
  a.path_points = 1;
  env.step(a, {obs.data(), r.data(), te.data(), tr.data()});
  EXPECT_EQ(env.status(0).distance_m, 0.0);
  EXPECT_EQ(te[0], 0);
}

TEST(LearnParams, AFileOverridesKeysAndBadKeysAreNamed) {
  const test::TempDir dir;
  const auto write = [&](const std::string& text) {
    const auto file = dir.path() / "learn.json";
    std::ofstream(file) << text;
    return file;
  };
  const EnvParams d = load_env_params(std::nullopt);
  EXPECT_EQ(d.decision_steps, 10);
  EXPECT_DOUBLE_EQ(d.reward.collision, 50.0);
  const EnvParams p =
      load_env_params(write(R"({"decision_steps": 5, "reward": {"collision": 9}})"));
  EXPECT_EQ(p.decision_steps, 5);
  EXPECT_DOUBLE_EQ(p.reward.collision, 9.0);
  EXPECT_DOUBLE_EQ(p.reward.at_fault, 50.0);
  EXPECT_EQ(env_params_json(p)["reward"]["collision"], 9.0);
  for (const auto& [text, words] : std::vector<std::pair<std::string, std::string>>{
           {R"({"reward": {"colision": 1}})", "reward.colision: is not a key"},
           {R"({"decision_steps": 0})", "decision_steps must be from 1 to 1000"},
           {R"({"decision_steps": 2.5})", "decision_steps: must be a whole number"},
           {R"({"terminate_on_collision": 1})", "must be true or false"},
           {R"([1])", "must be an object"}}) {
    try {
      (void)load_env_params(write(text));
      FAIL() << text;
    } catch (const run::ConfigError& e) {
      EXPECT_THAT(e.what(), HasSubstr(words)) << text;
    }
  }
  EXPECT_THROW(VecEnv(spec_of(0, 1)), std::invalid_argument);
  VecEnvSpec bad = spec_of(1, 1);
  bad.traffic = "heavy";
  EXPECT_THROW((VecEnv(bad)), std::invalid_argument);
}

}  // namespace
}  // namespace overtake::learn
