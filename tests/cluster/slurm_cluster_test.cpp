// `overtake bench --slurm` on a real Slurm cluster: munged, slurmctld and slurmd of the test's
// own (scripts/local-slurm.sh: a configuration, ports and folders of their own, stopped at the
// end, or by a guardian if the test is killed). A bench of 2 policies x 8 seeds runs as an
// array of 4 tasks; one task is cancelled part-way; overtake submits it again, and the merged
// result equals the same sweep benched locally, timing and host aside.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <csignal>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "bench_support.hpp"
#include "overtake/base/io.hpp"
#include "process_support.hpp"
#include "temp_dir.hpp"

namespace overtake {
namespace {

using nlohmann::json;
using ::testing::HasSubstr;
namespace fs = std::filesystem;
using namespace std::chrono_literals;

const fs::path kScript = fs::path(OVERTAKE_SOURCE_DIR) / "scripts" / "local-slurm.sh";

// The program `name` as PATH finds it; empty when it is not there.
std::string on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const fs::path file = fs::path(dir) / name;
    if (!dir.empty() && ::access(file.c_str(), X_OK) == 0) return file.string();
  }
  return "";
}

// Runs a command to its end (at most `timeout`); its exit status, and its output in `out`.
int run(const std::vector<std::string>& argv, const fs::path& out, const fs::path& err,
        std::chrono::milliseconds timeout = 120s) {
  const pid_t pid = test::start_command(argv, out, err);
  return test::exit_status(pid, timeout).value_or(-1);
}

std::size_t lines(const fs::path& file) {
  std::ifstream in(file);
  std::size_t n = 0;
  std::string line;
  while (std::getline(in, line)) n += line.empty() ? 0 : 1;
  return n;
}

class SlurmCluster : public ::testing::Test {
 protected:
  void SetUp() override {
    if (::geteuid() != 0) {
      GTEST_SKIP() << "a Slurm cluster of the test's own needs root (slurmd starts each job as "
                      "its user)";
    }
    for (const char* tool : {"munged", "slurmctld", "slurmd", "sbatch", "squeue", "scancel"}) {
      ASSERT_FALSE(on_path(tool).empty())
          << tool
          << " is missing: scripts/install-deps.sh installs slurmctld, "
             "slurmd, slurm-client and munge";
    }
    const fs::path out = dir_.path() / "start.out";
    const int rc = run({"/bin/bash", kScript.string(), "start", cluster_dir().string(), "--owner",
                        std::to_string(::getpid())},
                       out, dir_.path() / "start.err", 120s);
    started_ = true;
    ASSERT_EQ(rc, 0) << base::read_file(dir_.path() / "start.err");
    const std::string line = base::read_file(out);
    const std::string prefix = "export SLURM_CONF=";
    ASSERT_EQ(line.rfind(prefix, 0), 0u) << line;
    std::string conf = line.substr(prefix.size());
    conf.erase(conf.find_last_not_of("\n") + 1);
    ::setenv("SLURM_CONF", conf.c_str(), 1);
  }

  void TearDown() override {
    if (!started_) return;
    const int rc = run({"/bin/bash", kScript.string(), "stop", cluster_dir().string()},
                       dir_.path() / "stop.out", dir_.path() / "stop.err", 120s);
    EXPECT_EQ(rc, 0) << base::read_file(dir_.path() / "stop.err");
    ::unsetenv("SLURM_CONF");
  }

  [[nodiscard]] fs::path cluster_dir() const { return dir_.path() / "cluster"; }
  [[nodiscard]] fs::path path(const std::string& name) const { return dir_.path() / name; }

  // The array tasks in the queue, as "JOB_TASK STATE" lines.
  std::string queue() {
    (void)run({on_path("squeue"), "--noheader", "--array", "--format=%i %T"}, path("squeue.out"),
              path("squeue.err"));
    return base::read_file(path("squeue.out"));
  }

  test::TempDir dir_{"overtake-slurm-cluster"};
  bool started_ = false;
};

TEST_F(SlurmCluster, ABenchCancelledPartWayIsSubmittedAgainAndMergesIntoTheLocalResult) {
  const std::vector<std::string> sweep = {"bench",    "--policies", "reference,walkthrough",
                                          "--seeds",  "1-8",        "--traffic",
                                          "faithful", "--minutes",  "5"};
  std::vector<std::string> local = sweep;
  for (const char* a : {"--jobs", "2", "--quiet", "--out"}) local.emplace_back(a);
  local.push_back(path("local").string());
  local.insert(local.begin(), test::overtake_binary().string());
  ASSERT_EQ(run(local, path("local.out"), path("local.err"), 600s), 0)
      << base::read_file(path("local.err"));

  std::vector<std::string> slurm = sweep;
  for (const char* a : {"--slurm", "4", "--slurm-poll", "0.2", "--out"}) slurm.emplace_back(a);
  slurm.push_back(path("cluster-out").string());
  const pid_t bench = test::start_overtake(slurm, path("bench.out"), path("bench.err"));
  // Whatever happens below, the bench does not outlive the test (it would follow a cluster
  // that is gone, looking at its queue for ever).
  struct Reap {
    explicit Reap(pid_t p) : pid(p) {}
    pid_t pid;
    bool reaped = false;
    Reap(const Reap&) = delete;
    Reap& operator=(const Reap&) = delete;
    ~Reap() {
      if (reaped) return;
      ::kill(pid, SIGKILL);
      int status = 0;
      ::waitpid(pid, &status, 0);
    }
  } reap{bench};

  // Task 2 (reference seeds 2 and 6, walkthrough seeds 2 and 6): cancelled once it has written
  // a run of its four, or as soon as it runs if it is gone by then.
  const fs::path shard2 = path("cluster-out") / "shards" / "shard-2" / "runs.jsonl";
  std::string job2;
  const auto deadline = std::chrono::steady_clock::now() + 300s;
  while (job2.empty() && std::chrono::steady_clock::now() < deadline) {
    std::istringstream q(queue());
    std::string id, state;
    while (q >> id >> state) {
      if (id.size() > 2 && id.substr(id.size() - 2) == "_2" && state == "RUNNING") job2 = id;
    }
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_FALSE(job2.empty()) << "task 2 never ran:\n" << base::read_file(path("bench.err"));
  while (lines(shard2) < 1 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(20ms);
  }
  const std::size_t written = lines(shard2);
  ASSERT_EQ(run({on_path("scancel"), job2}, path("scancel.out"), path("scancel.err")), 0)
      << base::read_file(path("scancel.err"));

  const auto status = test::exit_status(bench, 600s);
  reap.reaped = true;  // waited for (and killed, past the time)
  const std::string err = base::read_file(path("bench.err"));
  ASSERT_EQ(status, 0) << err;
  // It was running when cancelled, with `written` of its 4 runs: overtake submits it again,
  // and the new task goes on from what the first wrote.
  EXPECT_THAT(err, HasSubstr("slurm: task 2 (job " + job2 + ") ended CANCELLED"));
  EXPECT_THAT(err, HasSubstr("with " + std::to_string(written)));
  EXPECT_THAT(err, HasSubstr("submitting it again (retry 1 of 2)"));
  const json state = json::parse(base::read_file(path("cluster-out") / "slurm" / "state.json"));
  EXPECT_EQ(state["attempts"][1].size(), 2u);
  EXPECT_EQ(state["attempts"][0].size(), 1u);
  EXPECT_THAT(base::read_file(path("bench.out")),
              HasSubstr("16 runs in 4 Slurm tasks (1 submitted again)"));
  EXPECT_EQ(test::stable_runs(path("cluster-out")), test::stable_runs(path("local")));
  EXPECT_EQ(test::untimed_summary(path("cluster-out")), test::untimed_summary(path("local")));
  EXPECT_EQ(base::read_file(path("cluster-out") / "pairs.csv"),
            base::read_file(path("local") / "pairs.csv"));
  EXPECT_EQ(lines(path("cluster-out") / "runs.jsonl"), 16u);
  // Nothing of the array is left in the queue.
  EXPECT_EQ(queue(), "");
}

}  // namespace
}  // namespace overtake
