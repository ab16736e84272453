// `overtake bench --slurm`: the batch script, what is read from sbatch, squeue and scontrol,
// the flags' checks, and the whole follow-resubmit-merge loop against stand-ins for Slurm's
// commands (a real cluster: tests/cluster).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>

#include "bench_support.hpp"
#include "overtake/app/cli.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/cluster/slurm.hpp"
#include "process_support.hpp"
#include "temp_dir.hpp"

namespace overtake::app {

using base::kExitFailure;
using base::kExitInterrupted;
using base::kExitUsage;
using base::read_file;
using base::shell_quote;
using base::UsageError;
using base::write_file_atomic;
using cluster::parse_sbatch_job_id;
using cluster::parse_scontrol_job;
using cluster::parse_squeue_tasks;
using cluster::slurm_batch_script;
using cluster::slurm_shard_runs;
using cluster::SlurmArray;
using cluster::SlurmJobEnd;
using cluster::SlurmOptions;
using cluster::validate_slurm_options;
namespace {

using nlohmann::json;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

// What `sh -c 'printf %s "$0"' WORD` prints for the word `quoted` (parsed by a real shell).
std::string through_sh(const std::string& quoted) {
  const test::TempDir dir("overtake-slurm-quote");
  const fs::path out = dir.path() / "out";
  const pid_t pid =
      test::start_command({"/bin/sh", "-c", "printf %s " + quoted}, out, dir.path() / "err");
  EXPECT_EQ(test::exit_status(pid, std::chrono::seconds(10)), 0);
  return read_file(out);
}

TEST(SlurmPieces, ShellQuotingSurvivesTheShell) {
  EXPECT_EQ(shell_quote("--seeds=1-20"), "--seeds=1-20");
  EXPECT_EQ(shell_quote("a b"), "'a b'");
  for (const std::string nasty : {"a b", "it's", "$(rm -rf /)", "`x`", "a\"b", "semi;colon", "",
                                  "new\nline", "star*", "--planner-cmd=OMP_NUM_THREADS=1 ./p"}) {
    EXPECT_EQ(through_sh(shell_quote(nasty)), nasty) << nasty;
  }
}

SlurmArray a_bench() {
  SlurmArray b;
  b.command = "bench";
  b.out = "/data/my results";
  b.binary = "/opt/overtake/bin/overtake";
  b.workdir = "/home/me/planners";
  b.args = {"--policies=reference,mine", "--planner-cmd=./mine --fast", "--planner-name=mine",
            "--seeds=1-200"};
  b.task_flags = {"--resume", "--quiet"};
  b.runs = 400;
  return b;
}

TEST(SlurmPieces, TheScriptRunsTheTasksShardWithResumeInItsFolder) {
  SlurmOptions o;
  o.tasks = 8;
  o.cpus_per_task = 4;
  o.partition = "short";
  o.time_limit = "2:00:00";
  o.sbatch_options = {"--account=lab", "--mem=4G"};
  const std::string s = slurm_batch_script(a_bench(), o);
  EXPECT_EQ(s.rfind("#!/bin/sh\n", 0), 0u);
  for (const char* line : {"#SBATCH --job-name=overtake-bench\n", "#SBATCH --array=1-8\n",
                           "#SBATCH --cpus-per-task=4\n", "#SBATCH --chdir=/home/me/planners\n",
                           "#SBATCH --output=\"/data/my results/slurm/logs/task-%a.job-%A.log\"\n",
                           "#SBATCH --partition=short\n", "#SBATCH --time=2:00:00\n",
                           "#SBATCH --account=lab\n", "#SBATCH --mem=4G\n"}) {
    EXPECT_THAT(s, HasSubstr(line));
  }
  EXPECT_THAT(s, HasSubstr("exec /opt/overtake/bin/overtake bench --policies=reference,mine "
                           "'--planner-cmd=./mine --fast' --planner-name=mine --seeds=1-200 "
                           "--shard=\"$SLURM_ARRAY_TASK_ID\"/8 "
                           "--out='/data/my results/shards/shard-'\"$SLURM_ARRAY_TASK_ID\" "
                           "--jobs=4 --resume --quiet\n"));
  // A task's command, as the shell reads it.
  const test::TempDir dir("overtake-slurm-script");
  write_file_atomic(dir.path() / "s.sh", s);
  EXPECT_EQ(test::exit_status(test::start_command({"/bin/sh", "-n", (dir.path() / "s.sh").string()},
                                                  "/dev/null", dir.path() / "err"),
                              std::chrono::seconds(10)),
            0)
      << read_file(dir.path() / "err");
}

TEST(SlurmPieces, WhatSlurmsCommandsAnswerIsRead) {
  EXPECT_EQ(parse_sbatch_job_id("4242\n"), "4242");
  EXPECT_EQ(parse_sbatch_job_id("4242;cluster-b\n"), "4242");
  EXPECT_THROW((void)parse_sbatch_job_id("Submitted batch job 4242"), std::runtime_error);
  EXPECT_THROW((void)parse_sbatch_job_id(""), std::runtime_error);

  const auto q = parse_squeue_tasks(
      "123_4 RUNNING\n123_[5-8] PENDING\n77 RUNNING\n\n123_2 COMPLETING\n99_1 PENDING\nx_y Z\n");
  ASSERT_EQ(q.size(), 3u);
  EXPECT_EQ(q[0].job, "123");
  EXPECT_EQ(q[0].task, 4);
  EXPECT_EQ(q[0].state, "RUNNING");
  EXPECT_EQ(q[1].task, 2);
  EXPECT_EQ(q[2].job, "99");

  const SlurmJobEnd end = parse_scontrol_job(
      "JobId=130 ArrayJobId=123 ArrayTaskId=3 JobName=overtake-bench\n"
      "   UserId=me(1000) GroupId=me(1000) MCS_label=N/A\n"
      "   JobState=CANCELLED Reason=None Dependency=(null)\n"
      "   Requeue=1 Restarts=0 BatchFlag=1 Reboot=0 ExitCode=0:15\n");
  EXPECT_EQ(end.state, "CANCELLED");
  EXPECT_EQ(end.exit_code, "0:15");
  EXPECT_EQ(end.reason, "");
  EXPECT_EQ(parse_scontrol_job("JobState=TIMEOUT Reason=TimeLimit ExitCode=0:0").reason,
            "TimeLimit");
  EXPECT_EQ(parse_scontrol_job("slurm_load_jobs error: Invalid job id specified").state, "");
}

TEST(SlurmPieces, TheShardsShareTheRunsOut) {
  std::size_t total = 0;
  for (int t = 1; t <= 4; ++t) total += slurm_shard_runs(10, 4, t);
  EXPECT_EQ(total, 10u);
  EXPECT_EQ(slurm_shard_runs(10, 4, 1), 3u);
  EXPECT_EQ(slurm_shard_runs(10, 4, 2), 3u);
  EXPECT_EQ(slurm_shard_runs(10, 4, 3), 2u);
  EXPECT_EQ(slurm_shard_runs(280, 8, 8), 35u);
}

TEST(SlurmPieces, BadOptionsAreRefusedNamingTheFlag) {
  const auto error = [](const SlurmOptions& o, std::size_t runs = 100) {
    try {
      validate_slurm_options(o, runs);
    } catch (const UsageError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  SlurmOptions ok;
  ok.tasks = 4;
  EXPECT_EQ(error(ok), "");
  SlurmOptions o = ok;
  o.tasks = 0;
  EXPECT_THAT(error(o), HasSubstr("--slurm: the number of tasks must be between 1"));
  EXPECT_THAT(error(ok, 3), HasSubstr("--slurm: 4 tasks for 3 runs"));
  o = ok;
  o.cpus_per_task = 0;
  EXPECT_THAT(error(o), HasSubstr("--slurm-cpus"));
  o = ok;
  o.retries = -1;
  EXPECT_THAT(error(o), HasSubstr("--slurm-retries"));
  o = ok;
  o.poll_s = 0.0;
  EXPECT_THAT(error(o), HasSubstr("--slurm-poll"));
  o = ok;
  o.partition = "a b";
  EXPECT_THAT(error(o), HasSubstr("--slurm-partition: 'a b'"));
  o = ok;
  o.time_limit = "1:00\n#SBATCH --x";
  EXPECT_THAT(error(o), HasSubstr("--slurm-time"));
  o = ok;
  o.sbatch_options = {"--array=1-3"};
  EXPECT_THAT(error(o), HasSubstr("--slurm-opt: --array is overtake's to set"));
  o.sbatch_options = {"account=lab"};
  EXPECT_THAT(error(o), HasSubstr("is not an sbatch option"));
  o.sbatch_options = {"--arrayish=1"};  // only the option itself is overtake's
  EXPECT_EQ(error(o), "");
}

// ----- against stand-ins for sbatch, squeue and scontrol ------------------------------------

// sbatch runs every task of the array at once, one after another, as Slurm would run the
// script (its folder, its log, SLURM_ARRAY_TASK_ID), and remembers how each ended; with a file
// `fail` in the stand-ins' folder, no task runs and each ends FAILED with a line in its log.
constexpr const char* kFakeSbatch = R"sh(#!/bin/sh
set -u
state="$FAKE_SLURM_DIR"
echo "$*" >> "$state/sbatch.calls"
script=""
array=""
for a in "$@"; do
  case "$a" in
    --array=*) array="${a#--array=}" ;;
    -*) ;;
    *) script="$a" ;;
  esac
done
[ -n "$array" ] || array=$(sed -n 's/^#SBATCH --array=//p' "$script")
job=$(cat "$state/next" 2>/dev/null || echo 100)
echo $((job + 1)) > "$state/next"
output=$(sed -n 's/^#SBATCH --output=//p' "$script" | tr -d '"')
chdir=$(sed -n 's/^#SBATCH --chdir=//p' "$script" | tr -d '"')
for range in $(echo "$array" | tr ',' ' '); do
  lo=${range%-*}
  hi=${range#*-}
  for t in $(seq "$lo" "$hi"); do
    log=$(echo "$output" | sed "s/%a/$t/; s/%A/$job/")
    if [ -f "$state/hold" ]; then
      echo "${job}_$t" >> "$state/held"
    elif [ -f "$state/fail" ]; then
      echo "overtake: error: the node said no" > "$log"
      echo "FAILED 2:0" > "$state/job-${job}_$t"
    else
      if (cd "$chdir" && SLURM_ARRAY_TASK_ID=$t sh "$script") > "$log" 2>&1; then
        echo "COMPLETED 0:0" > "$state/job-${job}_$t"
      else
        echo "FAILED 1:0" > "$state/job-${job}_$t"
      fi
      if [ -f "$state/late" ]; then  # Slurm still says RUNNING the first time it is asked
        mv "$state/job-${job}_$t" "$state/job-${job}_$t.final"
        echo "RUNNING 0:0" > "$state/job-${job}_$t"
      fi
    fi
  done
done
echo "$job"
)sh";

constexpr const char* kFakeSqueue = R"sh(#!/bin/sh
# Every task has run by the time sbatch answers, but those held (a file `hold`): they run on.
if [ -f "$FAKE_SLURM_DIR/held" ]; then sed 's/$/ RUNNING/' "$FAKE_SLURM_DIR/held"; fi
exit 0
)sh";

constexpr const char* kFakeScontrol = R"sh(#!/bin/sh
f="$FAKE_SLURM_DIR/job-$3"
if [ ! -f "$f" ]; then
  echo "slurm_load_jobs error: Invalid job id specified" >&2
  exit 1
fi
read -r st code < "$f"
if [ -f "$f.final" ]; then mv "$f.final" "$f"; fi
echo "JobId=$3 JobName=overtake-bench"
echo "   JobState=$st Reason=None Dependency=(null)"
echo "   Requeue=1 Restarts=0 BatchFlag=1 Reboot=0 ExitCode=$code"
)sh";

class SlurmCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const fs::path bin = dir_.path() / "bin";
    fs::create_directories(bin);
    fs::create_directories(fake());
    for (const auto& [name, text] :
         {std::pair{"sbatch", kFakeSbatch}, std::pair{"squeue", kFakeSqueue},
          std::pair{"scontrol", kFakeScontrol}}) {
      write_file_atomic(bin / name, text);
      fs::permissions(bin / name, fs::perms::owner_all);
    }
    const char* path = std::getenv("PATH");
    ::setenv("PATH", (bin.string() + ":" + (path ? path : "/usr/bin:/bin")).c_str(), 1);
    ::setenv("FAKE_SLURM_DIR", fake().c_str(), 1);
  }

  [[nodiscard]] fs::path fake() const { return dir_.path() / "fake"; }
  [[nodiscard]] fs::path path(const std::string& name) const { return dir_.path() / name; }

  // `overtake ARGS`: its exit status; its output in out.txt and err.txt.
  int run(const std::vector<std::string>& args) {
    const pid_t pid = test::start_overtake(args, path("out.txt"), path("err.txt"));
    return test::exit_status(pid, std::chrono::seconds(300)).value_or(-1);
  }
  [[nodiscard]] std::string out() const { return read_file(path("out.txt")); }
  [[nodiscard]] std::string err() const { return read_file(path("err.txt")); }
  [[nodiscard]] int sbatch_calls() const {
    if (!fs::exists(fake() / "sbatch.calls")) return 0;
    const std::string calls = read_file(fake() / "sbatch.calls");
    return static_cast<int>(std::count(calls.begin(), calls.end(), '\n'));
  }

  static std::vector<std::string> sweep() {
    return {"bench",     "--policies", "walkthrough,seed001", "--seeds", "1-3",
            "--traffic", "faithful",   "--minutes",           "1"};
  }
  static std::vector<std::string> with(std::vector<std::string> a,
                                       const std::vector<std::string>& more) {
    a.insert(a.end(), more.begin(), more.end());
    return a;
  }
  /// A tune of the planner and parameter `planner` names: 3 trials of seeds 1-2 x 0.5 min.
  static std::vector<std::string> small_tune(const std::vector<std::string>& planner) {
    return with(with({"tune"}, planner),
                {"--seeds", "1-2", "--minutes", "0.5", "--trials", "3", "--constraint", "none"});
  }
  /// Runs the tune `search` here (--jobs 2, into local/) and then on Slurm (2 tasks, into
  /// cluster/); true when both finished.
  bool tune_here_and_on_slurm(const std::vector<std::string>& search) {
    return run(with(search, {"--jobs", "2", "--out", path("local").string()})) == 0 &&
           run(with(search, {"--slurm", "2", "--slurm-poll", "0.1", "--out",
                             path("cluster").string()})) == 0;
  }
  /// The search on Slurm found what the search here found: the same trials, the same best.
  void expect_the_same_search() const {
    EXPECT_EQ(read_file(path("cluster") / "trials.jsonl"),
              read_file(path("local") / "trials.jsonl"));
    EXPECT_EQ(read_file(path("cluster") / "best.json"), read_file(path("local") / "best.json"));
  }
  /// A small tune on Slurm of an in-process planner's parameter (`planner`: its flags and
  /// --param) finds what the same search here finds, its trials drive differently (the value
  /// reached each task, as --planner-params), and each trial is one array.
  void expect_a_tune_on_slurm_of(const std::vector<std::string>& planner) {
    ASSERT_TRUE(tune_here_and_on_slurm(small_tune(planner))) << err();
    EXPECT_EQ(sbatch_calls(), 3);
    expect_the_same_search();
    std::set<std::string> speeds;
    std::ifstream trials(path("cluster") / "trials.jsonl");
    for (std::string line; std::getline(trials, line);)
      speeds.insert(json::parse(line)["figures"]["mean_speed_mph"].dump());
    EXPECT_EQ(speeds.size(), 3U);
  }

  test::TempDir dir_{"overtake-slurm-cli"};
};

TEST_F(SlurmCli, TheTasksShardsMergeIntoWhatALocalBenchWrites) {
  ASSERT_EQ(run(with(sweep(), {"--jobs", "2", "--quiet", "--out", path("local").string()})), 0)
      << err();
  // The report page when the build has the pages (the sanitizer build has none).
  std::vector<std::string> html;
  if (OVERTAKE_WEB_PAGES) html = {"--html", path("report.html").string()};
  ASSERT_EQ(
      run(with(
          sweep(),
          with({"--slurm", "3", "--slurm-poll", "0.1", "--out", path("cluster").string()}, html))),
      0)
      << err();
  EXPECT_EQ(sbatch_calls(), 1);
  EXPECT_THAT(err(), HasSubstr("slurm: submitted 3 tasks as job 100"));
  EXPECT_THAT(err(), HasSubstr("slurm: 3/3 tasks done"));
  EXPECT_THAT(out(), HasSubstr("6 runs in 3 Slurm tasks (0 submitted again)"));
  if (OVERTAKE_WEB_PAGES) {
    EXPECT_THAT(out(), HasSubstr("report: "));
    EXPECT_TRUE(fs::exists(path("report.html")));
  }
  for (int t = 1; t <= 3; ++t) {
    const json m = json::parse(
        read_file(path("cluster") / "shards" / ("shard-" + std::to_string(t)) / "bench.json"));
    EXPECT_EQ(m["shard"], std::to_string(t) + "/3");
  }
  EXPECT_EQ(test::stable_runs(path("cluster")), test::stable_runs(path("local")));
  EXPECT_EQ(test::untimed_summary(path("cluster")), test::untimed_summary(path("local")));
  EXPECT_EQ(read_file(path("cluster") / "pairs.csv"), read_file(path("local") / "pairs.csv"));
  // Done and merged: the folder is not a bench to follow again.
  EXPECT_EQ(run(with(sweep(), {"--slurm", "3", "--resume", "--out", path("cluster").string()})),
            kExitUsage);
  EXPECT_THAT(err(), HasSubstr("already holds bench results"));
}

TEST_F(SlurmCli, ATuneOnSlurmRunsEachBenchAsAnArrayAndFindsWhatALocalTuneFinds) {
  // A program's placeholder: each trial's tasks run the program with that trial's value.
  const std::string course =
      (fs::path(OVERTAKE_BINARY_DIR) / "tests" / "overtake_course_planner").string();
  const std::vector<std::string> search =
      with(small_tune({"--planner-cmd", course + " --speed-mps {speed}", "--planner-name", "course",
                       "--param", "speed=12:20@14"}),
           {"--validate-seeds", "5-6"});
  ASSERT_TRUE(tune_here_and_on_slurm(search)) << err();
  // Three trials and the validation's two benches, each an array of its own.
  EXPECT_EQ(sbatch_calls(), 5);
  EXPECT_THAT(err(), HasSubstr("as a Slurm array of 2 tasks"));
  expect_the_same_search();
  const std::string trial = (path("cluster") / "trials" / "0002").string();
  EXPECT_TRUE(fs::exists(fs::path(trial) / "shards" / "shard-2" / "runs.jsonl"));
  // Resumed when done: nothing is submitted again.
  ASSERT_EQ(run(with(search, {"--slurm", "2", "--slurm-poll", "0.1", "--resume", "--out",
                              path("cluster").string()})),
            0)
      << err();
  EXPECT_EQ(sbatch_calls(), 5);
}

TEST_F(SlurmCli, ATuneOnSlurmOfAPluginsParameterFindsWhatALocalTuneFinds) {
  // A plugin's setup parameter reaches each task as --planner-params.
  expect_a_tune_on_slurm_of({"--policy-lib", std::string("lane=") + OVERTAKE_KEEP_LANE_PLUGIN,
                             "--param", "cruise_mps=10:21@12"});
}

TEST_F(SlurmCli, ATuneOnSlurmOfAPythonPlannersKeywordFindsWhatALocalTuneFinds) {
  // A Python planner's keyword argument, the same way (the sanitizer build has no Python).
  if (!OVERTAKE_PYTHON_PLANNERS) GTEST_SKIP() << "this build runs no Python planners";
  const fs::path planner =
      fs::path(OVERTAKE_SOURCE_DIR) / "tests" / "python" / "planners" / "keyword_speed.py";
  expect_a_tune_on_slurm_of(
      {"--policy-py", "kw=" + planner.string() + ":Planner", "--param", "speed_mps=8:20@10"});
}

TEST_F(SlurmCli, WhatATuneOnSlurmCannotDoIsRefusedBeforeAnyTrial) {
  // More tasks than a bench has runs: refused before any trial.
  EXPECT_EQ(run({"tune", "--policy", "reference", "--param", "hysteresis=0:0.05", "--seeds", "1-2",
                 "--slurm", "3", "--out", path("many").string()}),
            kExitUsage);
  EXPECT_THAT(err(), HasSubstr("--slurm: 3 tasks for 2 runs"));
  EXPECT_FALSE(fs::exists(path("many") / "trials.jsonl"));
  EXPECT_EQ(run({"tune", "--policy", "reference", "--param", "hysteresis=0:0.05", "--seeds", "1-2",
                 "--slurm", "2", "--slurm-submit-only", "--out", path("only").string()}),
            kExitUsage);
  EXPECT_THAT(err(), HasSubstr("--slurm-submit-only: a search reads each trial's bench"));
  EXPECT_EQ(sbatch_calls(), 0);
}

// hunt.json of a folder, its timing left out and the folder named OUT.
std::string hunt_report(const fs::path& dir) {
  json j = json::parse(read_file(dir / "hunt.json"));
  j.erase("timing");
  std::string text = j.dump(1);
  for (auto at = text.find(dir.string()); at != std::string::npos; at = text.find(dir.string()))
    text.replace(at, dir.string().size(), "OUT");
  return text;
}

TEST_F(SlurmCli, AHuntOnSlurmFindsWhatALocalHuntFinds) {
  const std::vector<std::string> hunt = {"hunt",     "--policy",       "seed001", "--traffic",
                                         "faithful", "--minutes",      "2",       "--failures",
                                         "3",        "--budget-hours", "1"};
  ASSERT_EQ(run(with(hunt, {"--jobs", "2", "--quiet", "--out", path("local").string()})), 0)
      << err();
  ASSERT_EQ(
      run(with(hunt, {"--slurm", "3", "--slurm-poll", "0.1", "--out", path("cluster").string()})),
      0)
      << err();
  EXPECT_EQ(sbatch_calls(), 1);
  EXPECT_THAT(err(), HasSubstr("slurm: submitted 3 tasks as job 100"));
  EXPECT_THAT(err(), HasSubstr("failures found"));
  EXPECT_THAT(out(), HasSubstr("3 Slurm tasks (0 submitted again)"));
  EXPECT_TRUE(fs::exists(path("cluster") / "slurm" / "hunt.sbatch"));
  EXPECT_EQ(hunt_report(path("cluster")), hunt_report(path("local")));
  // The shards merge by hand the same way.
  const fs::path shards = path("cluster") / "shards";
  ASSERT_EQ(run({"hunt", "merge", (shards / "shard-1").string(), (shards / "shard-2").string(),
                 (shards / "shard-3").string(), "--out", path("by-hand").string()}),
            0)
      << err();
  EXPECT_EQ(hunt_report(path("by-hand")), hunt_report(path("local")));
  EXPECT_EQ(run(with(hunt, {"--resume", "--out", path("x").string()})), kExitUsage);
  EXPECT_THAT(err(), HasSubstr("--resume goes with --slurm TASKS"));
}

// risk.json without what differs between one run here and a merge: the wall time, the folder,
// the merge's own note.
json risk_figures(const fs::path& dir) {
  json j = json::parse(read_file(dir / "risk.json"));
  for (const char* key : {"wall_s", "merged", "scenarios"}) j.erase(key);
  return j;
}

TEST_F(SlurmCli, ARiskOnSlurmGivesTheEstimateOfOneRunHere) {
  const std::vector<std::string> risk = {
      "risk",       "--policy", "seed003",     "--event", "near-miss",   "--minutes", "3",
      "--max-runs", "20",       "--rel-error", "0.6",     "--scenarios", "0"};
  ASSERT_EQ(run(with(risk, {"--jobs", "2", "--quiet", "--out", path("local").string()})), 0)
      << err();
  ASSERT_EQ(
      run(with(risk, {"--slurm", "3", "--slurm-poll", "0.1", "--out", path("cluster").string()})),
      0)
      << err();
  EXPECT_EQ(sbatch_calls(), 1);
  EXPECT_THAT(err(), HasSubstr("slurm: submitted 3 tasks as job 100"));
  EXPECT_TRUE(fs::exists(path("cluster") / "slurm" / "risk.sbatch"));
  EXPECT_THAT(out(), HasSubstr("3 Slurm tasks (0 submitted again)"));
  EXPECT_THAT(out(), HasSubstr("| merged | 3 of 3 shards, 20 runs"));
  const json local = risk_figures(path("local"));
  ASSERT_EQ(local["stopped_by"], "rel-error");  // before the 20 runs the shards ran
  EXPECT_LT(local["runs"].get<int>(), 20);
  EXPECT_EQ(risk_figures(path("cluster")), local);
  // The shards merge by hand the same way, with the same flags.
  const fs::path shards = path("cluster") / "shards";
  ASSERT_EQ(run(with(risk, {"--merge", (shards / "shard-1").string(), (shards / "shard-2").string(),
                            (shards / "shard-3").string(), "--out", path("by-hand").string()})),
            0)
      << err();
  EXPECT_EQ(risk_figures(path("by-hand")), local);
  // A shard of another estimate is refused, naming what differs.
  EXPECT_EQ(run({"risk", "--event", "contact", "--merge", (shards / "shard-1").string(), "--out",
                 path("other").string()}),
            kExitUsage);
  EXPECT_THAT(err(), HasSubstr("is a shard of another"));
  EXPECT_EQ(run(with(risk, {"--slurm", "2", "--shard", "1/2", "--out", path("x").string()})),
            kExitUsage);
  EXPECT_THAT(err(), HasSubstr("--slurm makes the shards itself"));
}

TEST_F(SlurmCli, ATaskThatFailsEveryTimeIsGivenUpOnSayingWhyAndResumeSubmitsItAgain) {
  write_file_atomic(fake() / "fail", "");
  const auto args = with(sweep(), {"--slurm", "2", "--slurm-retries", "1", "--slurm-poll", "0.1",
                                   "--out", path("cluster").string()});
  EXPECT_EQ(run(args), kExitFailure);
  EXPECT_EQ(sbatch_calls(), 2);  // the array, then both tasks again in one submission
  EXPECT_THAT(err(), HasSubstr("slurm: task 1 (job 100_1) ended FAILED (exit 2:0) with 0 of 3 "
                               "runs: overtake: error: the node said no; submitting it again "
                               "(retry 1 of 1)"));
  EXPECT_THAT(err(), HasSubstr("task 2 (job 101_2) ended FAILED (exit 2:0) with 0 of 3 runs: "
                               "overtake: error: the node said no; giving up on it"));
  EXPECT_THAT(err(), HasSubstr("2 Slurm tasks did not finish"));
  EXPECT_THAT(err(), HasSubstr("with --resume submits the rest again"));
  EXPECT_FALSE(fs::exists(path("cluster") / "runs.jsonl"));
  // Without --resume the folder is refused; with it, the tasks are submitted again.
  EXPECT_EQ(run(args), kExitUsage);
  EXPECT_THAT(err(), HasSubstr("holds a Slurm bench already"));
  // Another sweep, or another number of tasks, is not taken for this one.
  EXPECT_EQ(run(with(sweep(), {"--slurm", "3", "--resume", "--out", path("cluster").string()})),
            kExitUsage);
  EXPECT_THAT(err(), HasSubstr("holds a different Slurm bench"));
  fs::remove(fake() / "fail");
  EXPECT_EQ(run(with(args, {"--resume"})), 0) << err();
  EXPECT_EQ(sbatch_calls(), 3);
  EXPECT_THAT(out(), HasSubstr("6 runs in 2 Slurm tasks (2 submitted again)"));
  const json state = json::parse(read_file(path("cluster") / "slurm" / "state.json"));
  EXPECT_EQ(state["attempts"][0], json({"100", "101", "102"}));
}

// A task that squeue no longer lists but scontrol says still runs (the listing raced its
// start, or it was requeued) is left alone: submitting it again would run its shard twice.
TEST_F(SlurmCli, ATaskSlurmStillHoldsIsNotSubmittedAgain) {
  write_file_atomic(fake() / "late", "");
  ASSERT_EQ(run(with(sweep(),
                     {"--slurm", "2", "--slurm-poll", "0.1", "--out", path("cluster").string()})),
            0)
      << err();
  EXPECT_EQ(sbatch_calls(), 1);
  EXPECT_THAT(err(), HasSubstr("0/2 tasks done, 2 running"));
  EXPECT_THAT(out(), HasSubstr("6 runs in 2 Slurm tasks (0 submitted again)"));
}

// Ctrl-C stops following, not the tasks: they are named, and --resume follows them again.
TEST_F(SlurmCli, CtrlCStopsFollowingAndLeavesTheTasksRunning) {
  write_file_atomic(fake() / "hold", "");
  const pid_t pid = test::start_overtake(
      with(sweep(), {"--slurm", "2", "--slurm-poll", "0.1", "--out", path("cluster").string()}),
      path("out.txt"), path("err.txt"));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!fs::exists(fake() / "held") && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // following by now
  ::kill(pid, SIGINT);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(test::exit_status(pid, std::chrono::seconds(30)), kExitInterrupted);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
  EXPECT_THAT(err(), HasSubstr("0/2 tasks done, 2 running"));
  EXPECT_THAT(err(), HasSubstr("stopped following; the tasks go on in Slurm (jobs 100)"));
  EXPECT_THAT(err(), HasSubstr("scancel 100 cancels them"));
  // Taken up again: the held tasks end (here: they ran), overtake merges.
  fs::remove(fake() / "hold");
  fs::remove(fake() / "held");
  EXPECT_EQ(run(with(sweep(), {"--slurm", "2", "--slurm-poll", "0.1", "--resume", "--out",
                               path("cluster").string()})),
            0)
      << err();
  EXPECT_EQ(sbatch_calls(), 2);  // the held tasks never ran: both submitted again
  EXPECT_THAT(out(), HasSubstr("6 runs in 2 Slurm tasks (2 submitted again)"));
}

TEST_F(SlurmCli, SubmitOnlyReturnsAtOnceSayingHowToFollow) {
  write_file_atomic(fake() / "fail", "");  // nothing runs: the tasks are "still out there"
  ASSERT_EQ(run(with(sweep(),
                     {"--slurm", "2", "--slurm-submit-only", "--out", path("cluster").string()})),
            0)
      << err();
  EXPECT_EQ(sbatch_calls(), 1);
  EXPECT_THAT(out(), HasSubstr("submitted: jobs 100"));
  EXPECT_THAT(out(), HasSubstr("the same command with --resume instead of --slurm-submit-only"));
  EXPECT_THAT(out(), HasSubstr("overtake bench merge " + (path("cluster") / "shards").string() +
                               "/shard-* --out " + path("cluster").string()));
  EXPECT_FALSE(fs::exists(path("cluster") / "runs.jsonl"));
  EXPECT_TRUE(fs::exists(path("cluster") / "slurm" / "bench.sbatch"));
}

TEST_F(SlurmCli, BadInputIsRefusedBeforeAnythingIsSubmitted) {
  const auto refused = [&](const std::vector<std::string>& more, const std::string& what) {
    EXPECT_EQ(run(with(sweep(), with(more, {"--out", path("x").string()}))), kExitUsage)
        << what << "\n"
        << err();
    EXPECT_THAT(err(), HasSubstr(what));
  };
  refused({"--slurm-time", "1:00:00"}, "--slurm-time goes with --slurm TASKS");
  refused({"--slurm", "2", "--shard", "1/2"}, "--slurm makes the shards itself");
  refused({"--slurm", "7"}, "--slurm: 7 tasks for 6 runs");
  refused({"--slurm", "2", "--slurm-opt=--output=x.log"}, "--output is overtake's to set");
  refused({"--slurm", "2", "--slurm-cpus", "0"}, "--slurm-cpus");
  EXPECT_EQ(run({"bench", "--policies", "nobody", "--slurm", "1", "--out", path("x").string()}),
            kExitUsage);
  EXPECT_THAT(err(), HasSubstr("nobody"));
  EXPECT_EQ(sbatch_calls(), 0);
  EXPECT_FALSE(fs::exists(path("x") / "slurm" / "state.json"));
}

}  // namespace
}  // namespace overtake::app
