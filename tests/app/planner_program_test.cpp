// Planner programs started by overtake (`--planner-cmd`): a program in the test tree that
// behaves like the course's (fixed port 4567, a line of output per message, abort on
// disconnect) is benched in parallel beside a built-in policy, gives the same report as that
// policy in-process, and its failures (crash, hang, never listening, exiting at once) each end
// their run with a clear reason while the bench goes on. Also the catalog's names and the
// process keeper on its own.

#include <gtest/gtest.h>

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/app/commands.hpp"
#include "overtake/app/planner_process.hpp"
#include "overtake/app/planners.hpp"
#include "process_support.hpp"

namespace overtake {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path course_planner() {
  return fs::path(OVERTAKE_BINARY_DIR) / "tests" / "overtake_course_planner";
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<json> read_rows(const fs::path& file) {
  std::vector<json> rows;
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty()) rows.push_back(json::parse(line));
  }
  return rows;
}

// The report without what may differ between a program and an in-process policy: the time
// figures and the run's configuration (name, provenance).
json stable(json row) {
  for (const char* k : {"timing", "config", "index", "provenance"}) row.erase(k);
  return row;
}

class PlannerProgramTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    root_ = fs::temp_directory_path() /
            (std::string("overtake-programs-") + info->name() + "-" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  // Runs the binary; returns its exit status, with its stdout and stderr in out_/err_.
  int run(const std::vector<std::string>& args,
          std::chrono::seconds timeout = std::chrono::seconds(300)) {
    const pid_t pid = test::start_overtake(args, root_ / "stdout", root_ / "stderr");
    const auto status = test::exit_status(pid, timeout);
    out_ = read_text(root_ / "stdout");
    err_ = read_text(root_ / "stderr");
    return status.value_or(-1);
  }

  fs::path root_;
  std::string out_, err_;
};

TEST(PlannerCatalogTest, NamesFromFlagsAndTheirErrors) {
  EXPECT_EQ(app::split_named("course=./planner --fast"),
            (std::pair<std::string, std::string>{"course", "./planner --fast"}));
  EXPECT_EQ(app::split_named("env X=1 ./planner").first, "");  // a space before '=': no name
  EXPECT_EQ(app::split_named("./build/planner").first, "");

  app::PlannerFlags flags;
  flags.commands = {"./build/path_planning", "mine=./other --x"};
  const auto catalog = app::catalog_from_flags(flags);
  EXPECT_EQ(catalog->added_names(), (std::vector<std::string>{"path_planning", "mine"}));
  const app::PlannerEntry* e = catalog->find("mine");
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->kind, app::PlannerKind::program);
  EXPECT_EQ(e->program->command, "./other --x");
  EXPECT_EQ(e->program->port, 4567);
  ASSERT_NE(catalog->find("reference"), nullptr);
  EXPECT_EQ(catalog->find("reference")->kind, app::PlannerKind::builtin);
  EXPECT_EQ(catalog->find("nobody"), nullptr);

  flags.commands = {"reference=./planner"};  // a built-in policy's name
  EXPECT_THROW((void)app::catalog_from_flags(flags), app::UsageError);
  flags.commands = {"a=./p", "a=./q"};
  EXPECT_THROW((void)app::catalog_from_flags(flags), app::UsageError);
  flags.commands = {"a=   "};
  EXPECT_THROW((void)app::catalog_from_flags(flags), app::UsageError);
}

TEST(PlannerProcessTest, OutputGoesToTheLogAndStopEndsTheWholeGroup) {
  const fs::path log =
      fs::temp_directory_path() / ("overtake-keeper-" + std::to_string(::getpid()) + ".log");
  app::PlannerProcessOptions o;
  o.command = "echo started; sleep 30 & sleep 30";
  o.log = log;
  o.isolated = false;
  app::PlannerProcess p(o);
  for (int i = 0; i < 200 && read_text(log).empty(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_EQ(p.ended(), "");
  p.stop(0.2);
  EXPECT_NE(p.ended().find("killed by signal 15"), std::string::npos) << p.ended();
  EXPECT_EQ(read_text(log), "started\n");
  fs::remove(log);
}

TEST(PlannerProcessTest, ALogIsCutAtItsLimitAndTheProgramIsNotHeldUp) {
  const fs::path log =
      fs::temp_directory_path() / ("overtake-cut-" + std::to_string(::getpid()) + ".log");
  app::PlannerProcessOptions o;
  o.command = "head -c 3000000 /dev/zero | tr '\\0' x; echo done >&2; exit 4";
  o.log = log;
  o.isolated = false;
  o.log_max_bytes = 1000;
  app::PlannerProcess p(o);
  std::string ended;
  for (int i = 0; i < 1000 && ended.empty(); ++i) {  // it writes 3 MB: it must not block
    ended = p.ended();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(ended, "exited with status 4");
  p.stop();
  const std::string text = read_text(log);
  EXPECT_EQ(text.substr(0, 1000), std::string(1000, 'x'));
  EXPECT_NE(text.find("the log is cut here"), std::string::npos);
  EXPECT_LT(text.size(), 1200u);
  fs::remove(log);
}

TEST(PlannerProcessTest, AProgramThatExitsSaysHow) {
  const fs::path log =
      fs::temp_directory_path() / ("overtake-exit-" + std::to_string(::getpid()) + ".log");
  app::PlannerProcessOptions o;
  o.command = "exit 7";
  o.log = log;
  o.isolated = false;
  app::PlannerProcess p(o);
  std::string ended;
  for (int i = 0; i < 300 && ended.empty(); ++i) {
    ended = p.ended();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(ended, "exited with status 7");
  o.cwd = "/no/such/folder";
  EXPECT_THROW(app::PlannerProcess{o}, std::runtime_error);
  fs::remove(log);
}

// Two programs on the same fixed port at once, each in its own network; the host's port
// stays closed, so nothing else on the machine reaches them.
TEST(PlannerProcessTest, IsolatedProgramsShareTheFixedPortAndNobodyElseReachesThem) {
  std::string why;
  if (!app::private_network_available(&why)) GTEST_SKIP() << why;
  const fs::path dir = fs::temp_directory_path() / ("overtake-iso-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  app::PlannerProcessOptions o;
  o.command = course_planner().string();
  o.isolated = true;
  o.log = dir / "a.log";
  app::PlannerProcess a(o);
  o.log = dir / "b.log";
  app::PlannerProcess b(o);
  const auto connect_in = [](app::PlannerProcess& p) {
    for (int i = 0; i < 500; ++i) {
      const int fd = p.open_socket();
      if (fd < 0) return false;
      sockaddr_in to{};
      to.sin_family = AF_INET;
      to.sin_port = htons(4567);
      to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      const bool ok = ::connect(fd, reinterpret_cast<const sockaddr*>(&to), sizeof to) == 0;
      ::close(fd);
      if (ok) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  };
  EXPECT_TRUE(connect_in(a));
  EXPECT_TRUE(connect_in(b));
  // Both listened on 4567 at once (each then aborts on the disconnect, as such programs do).
  EXPECT_NE(read_text(dir / "a.log").find("Listening to port 4567"), std::string::npos);
  EXPECT_NE(read_text(dir / "b.log").find("Listening to port 4567"), std::string::npos);
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(4567);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  EXPECT_NE(::connect(fd, reinterpret_cast<const sockaddr*>(&to), sizeof to), 0)
      << "the host's port 4567 answered: the planner is not isolated";
  ::close(fd);
  a.stop();
  b.stop();
  fs::remove_all(dir);
}

// The course-like program beside the built-in walkthrough it wraps, on 2 jobs: the program's
// reports equal the in-process ones, and each run's output is in its own log.
TEST_F(PlannerProgramTest, BenchRunsProgramsInParallelWithTheSameReportsAsInProcess) {
  const fs::path out = root_ / "bench";
  ASSERT_EQ(run({"bench", "--policies", "walkthrough", "--planner-cmd",
                 "course=" + course_planner().string(), "--seeds", "1-3", "--minutes", "1",
                 "--traffic", "faithful", "--jobs", "2", "--out", out.string(), "--quiet"}),
            0)
      << err_;
  const auto rows = read_rows(out / "runs.jsonl");
  ASSERT_EQ(rows.size(), 6u);
  std::map<std::pair<std::string, std::uint64_t>, json> by;
  for (const json& r : rows) {
    by[{r["config"]["policy"].get<std::string>(), r["config"]["seed"].get<std::uint64_t>()}] = r;
  }
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const json& program = by.at({"course", seed});
    const json& builtin = by.at({"walkthrough", seed});
    EXPECT_EQ(program["end"], "completed") << program["ended_early"];
    EXPECT_EQ(stable(program).dump(), stable(builtin).dump()) << "seed " << seed;
    EXPECT_EQ(program["config"]["planner"]["kind"], "program");
    const fs::path log = program["config"]["planner_log"].get<std::string>();
    EXPECT_EQ(log, out / "logs" / ("course-faithful-seed" + std::to_string(seed) + ".log"));
    const std::string text = read_text(log);
    EXPECT_NE(text.find("Listening to port 4567"), std::string::npos);
    EXPECT_GT(std::count(text.begin(), text.end(), '\n'), 1000);  // a line per message
    EXPECT_FALSE(builtin["config"].contains("planner"));
  }
  const json manifest = json::parse(read_text(out / "bench.json"));
  EXPECT_EQ(manifest["policies"], json({"walkthrough", "course"}));
  EXPECT_EQ(manifest["planners"]["course"]["kind"], "program");
}

// Each way a program can fail ends its own run with the reason; the bench goes on.
TEST_F(PlannerProgramTest, CrashesHangsAndSilentProgramsEndTheirRunsWithTheReason) {
  const std::string p = course_planner().string();
  const fs::path out = root_ / "bench";
  ASSERT_EQ(run({"bench",
                 "--planner-cmd",
                 "crash=" + p + " --crash-after 30",
                 "--planner-cmd",
                 "hang=" + p + " --hang-after 30",
                 "--planner-cmd",
                 "silent=" + p + " --never-listen",
                 "--planner-cmd",
                 "quits=" + p + " --exit-at-start",
                 "--planner-cmd",
                 "good=" + p,
                 "--planner-start-timeout",
                 "1",
                 "--planner-reply-timeout",
                 "0.5",
                 "--seeds",
                 "1",
                 "--minutes",
                 "1",
                 "--traffic",
                 "faithful",
                 "--jobs",
                 "2",
                 "--out",
                 out.string(),
                 "--quiet"}),
            0)
      << err_;
  std::map<std::string, json> by;
  for (const json& r : read_rows(out / "runs.jsonl")) by[r["config"]["policy"]] = r;
  ASSERT_EQ(by.size(), 5u);
  EXPECT_EQ(by["good"]["end"], "completed");
  const auto reason = [&](const std::string& name) {
    EXPECT_EQ(by[name]["end"], "planner_failed") << name;
    return by[name]["ended_early"].is_string() ? by[name]["ended_early"].get<std::string>() : "";
  };
  const std::string crash = reason("crash");
  EXPECT_NE(crash.find("signal 6"), std::string::npos) << crash;
  EXPECT_NE(crash.find("crash-faithful-seed1.log"), std::string::npos) << crash;
  EXPECT_GT(by["crash"]["planner_cycles"].get<long>(), 25);
  const std::string hang = reason("hang");
  EXPECT_NE(hang.find("stalled"), std::string::npos) << hang;
  const std::string silent = reason("silent");
  EXPECT_NE(silent.find("did not listen on port 4567"), std::string::npos) << silent;
  const std::string quits = reason("quits");
  EXPECT_NE(quits.find("exited with status 3"), std::string::npos) << quits;
  EXPECT_EQ(by["quits"]["planner_cycles"], 0);
}

// `sim --planner-cmd`: one program, one run, the report and the log where asked.
TEST_F(PlannerProgramTest, SimStartsTheProgramDrivesItAndStopsIt) {
  const fs::path json_path = root_ / "run.json";
  const fs::path log = root_ / "planner.log";
  ASSERT_EQ(run({"sim", "--planner-cmd", course_planner().string(), "--minutes", "1", "--seed", "2",
                 "--json", json_path.string(), "--planner-log", log.string(), "--quiet"}),
            0)
      << err_;
  const json report = json::parse(read_text(json_path));
  EXPECT_EQ(report["config"]["policy"], "overtake_course_planner");
  EXPECT_EQ(report["end"], "completed");
  EXPECT_NE(read_text(log).find("Connected!!!"), std::string::npos);

  EXPECT_EQ(run({"sim", "--planner", "ws://127.0.0.1:4567", "--planner-cmd", "x"}), 2);
  EXPECT_NE(err_.find("give one of them"), std::string::npos) << err_;
  EXPECT_EQ(run({"sim", "--minutes", "1"}), 2);
  EXPECT_NE(err_.find("--planner-cmd"), std::string::npos) << err_;
}

// On the host's network the runs take turns on the port, and still give the same reports.
TEST_F(PlannerProgramTest, OnTheHostNetworkRunsTakeTurns) {
  const fs::path out = root_ / "bench";
  ASSERT_EQ(
      run({"bench", "--planner-cmd", "course=" + course_planner().string() + " --port 45871",
           "--planner-port", "45871", "--planner-network", "host", "--seeds", "1-2", "--minutes",
           "0.5", "--traffic", "calm", "--jobs", "2", "--out", out.string(), "--quiet"}),
      0)
      << err_;
  const auto rows = read_rows(out / "runs.jsonl");
  ASSERT_EQ(rows.size(), 2u);
  for (const json& r : rows) EXPECT_EQ(r["end"], "completed") << r["ended_early"];
}

// The example program (examples/program) drives a few minutes in both kinds of traffic
// without an incident.
TEST_F(PlannerProgramTest, TheExampleProgramDrivesWithoutIncidents) {
  const fs::path program = fs::path(OVERTAKE_BINARY_DIR) / "tests" / "overtake_example_program";
  const std::string map = (fs::path(OVERTAKE_SOURCE_DIR) / "data/tracks/default.csv").string();
  const fs::path out = root_ / "bench";
  ASSERT_EQ(run({"bench", "--planner-cmd", "example=" + program.string() + " " + map, "--seeds",
                 "1-2", "--minutes", "4", "--jobs", "2", "--out", out.string(), "--quiet"}),
            0)
      << err_;
  const auto rows = read_rows(out / "runs.jsonl");
  ASSERT_EQ(rows.size(), 4u);
  for (const json& r : rows) {
    EXPECT_EQ(r["end"], "completed") << r["ended_early"];
    EXPECT_EQ(r["incident_counts"]["collision"], 0) << r["config"];
    EXPECT_EQ(r["incidents"].size(), 0u) << r["incidents"];
    EXPECT_GT(r["mean_speed_mph"].get<double>(), 40.0) << r["config"];
  }
}

}  // namespace
}  // namespace overtake
