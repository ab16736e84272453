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

#include <sys/wait.h>

#include <algorithm>
#include <csignal>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/base/errors.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/sandbox/planner_process.hpp"
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
// figures, the run's configuration (name, provenance), and the plan status (which only a
// planner in the process can tell).
json stable(json row) {
  for (const char* k : {"timing", "config", "index", "provenance", "plan_status"}) row.erase(k);
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
  EXPECT_EQ(planners::split_named("course=./planner.so"),
            (std::pair<std::string, std::string>{"course", "./planner.so"}));
  EXPECT_EQ(planners::split_named("./build/planner").first, "");

  planners::PlannerFlags flags;
  flags.commands = {"./build/path_planning", "./other --x"};
  flags.names = {"", "mine"};  // "": the program's own name
  auto catalog = planners::catalog_from_flags(flags);
  EXPECT_EQ(catalog->added_names(), (std::vector<std::string>{"path_planning", "mine"}));
  const planners::PlannerEntry* e = catalog->find("mine");
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->kind, planners::PlannerKind::program);
  EXPECT_EQ(e->program->command, "./other --x");
  EXPECT_EQ(e->program->port, 4567);
  ASSERT_NE(catalog->find("reference"), nullptr);
  EXPECT_EQ(catalog->find("reference")->kind, planners::PlannerKind::builtin);
  EXPECT_EQ(catalog->find("nobody"), nullptr);

  // A command is a shell command, whole: a variable before the program is a variable, and the
  // name comes from the program it runs.
  flags.names.clear();
  flags.commands = {"OMP_NUM_THREADS=1 ./build/path_planning --fast", "exec 'my dir/planner'",
                    "A=\"x y\" env B=2 ./third"};
  catalog = planners::catalog_from_flags(flags);
  EXPECT_EQ(catalog->added_names(),
            (std::vector<std::string>{"path_planning", "planner", "third"}));
  EXPECT_EQ(catalog->find("path_planning")->program->command,
            "OMP_NUM_THREADS=1 ./build/path_planning --fast");

  flags.commands = {"mine=./path_planning"};  // the old NAME=CMD: a variable, and no program
  try {
    (void)planners::catalog_from_flags(flags);
    ADD_FAILURE() << "an assignment alone was taken for a program";
  } catch (const base::UsageError& err) {
    EXPECT_NE(std::string(err.what()).find("--planner-name"), std::string::npos) << err.what();
  }
  flags.commands = {"./p", "./q"};
  flags.names = {"only-one"};
  EXPECT_THROW((void)planners::catalog_from_flags(flags), base::UsageError);
  flags.names = {"reference", "q"};  // a built-in policy's name
  EXPECT_THROW((void)planners::catalog_from_flags(flags), base::UsageError);
  flags.names = {"a", "a"};
  EXPECT_THROW((void)planners::catalog_from_flags(flags), base::UsageError);
  flags.commands = {"   "};
  flags.names.clear();
  EXPECT_THROW((void)planners::catalog_from_flags(flags), base::UsageError);
}

TEST(PlannerProcessTest, OutputGoesToTheLogAndStopEndsTheWholeGroup) {
  const fs::path log =
      fs::temp_directory_path() / ("overtake-keeper-" + std::to_string(::getpid()) + ".log");
  sandbox::PlannerProcessOptions o;
  o.command = "echo started; sleep 30 & sleep 30";
  o.log = log;
  o.isolated = false;
  sandbox::PlannerProcess p(o);
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
  sandbox::PlannerProcessOptions o;
  o.command = "head -c 3000000 /dev/zero | tr '\\0' x; echo done >&2; exit 4";
  o.log = log;
  o.isolated = false;
  o.log_max_bytes = 1000;
  sandbox::PlannerProcess p(o);
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
  sandbox::PlannerProcessOptions o;
  o.command = "exit 7";
  o.log = log;
  o.isolated = false;
  sandbox::PlannerProcess p(o);
  std::string ended;
  for (int i = 0; i < 300 && ended.empty(); ++i) {
    ended = p.ended();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(ended, "exited with status 7");
  o.cwd = "/no/such/folder";
  EXPECT_THROW(sandbox::PlannerProcess{o}, std::runtime_error);
  fs::remove(log);
}

// A TCP port on the host's loopback that is free now (the tests never count on a fixed one).
int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in at{};
  at.sin_family = AF_INET;
  at.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof at;
  EXPECT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&at), sizeof at), 0);
  EXPECT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&at), &len), 0);
  ::close(fd);
  return ntohs(at.sin_port);
}

sockaddr_in loopback(int port) {
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(port));
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return to;
}

// Two programs on the same port at once, each in its own network, while a listener of the
// test holds that very port on the host: the programs still start, and a connection on the
// host reaches the test's listener, never a planner. (Any port does: the test takes a free
// one and holds it, so that whatever else runs on this machine, 4567 included, plays no part.)
TEST(PlannerProcessTest, IsolatedProgramsShareOnePortAndNobodyElseReachesThem) {
  std::string why;
  if (!sandbox::private_network_available(&why)) GTEST_SKIP() << why;
  const fs::path dir = fs::temp_directory_path() / ("overtake-iso-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const int port = free_port();
  const int host = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  const sockaddr_in at = loopback(port);
  ASSERT_EQ(::bind(host, reinterpret_cast<const sockaddr*>(&at), sizeof at), 0);
  ASSERT_EQ(::listen(host, 4), 0);

  sandbox::PlannerProcessOptions o;
  o.command = course_planner().string() + " --port " + std::to_string(port);
  o.isolated = true;
  o.log = dir / "a.log";
  sandbox::PlannerProcess a(o);
  o.log = dir / "b.log";
  sandbox::PlannerProcess b(o);
  const auto connect_in = [port](sandbox::PlannerProcess& p) {
    for (int i = 0; i < 500; ++i) {
      const int fd = p.open_socket();
      if (fd < 0) return false;
      const sockaddr_in to = loopback(port);
      const bool ok = ::connect(fd, reinterpret_cast<const sockaddr*>(&to), sizeof to) == 0;
      ::close(fd);
      if (ok) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  };
  EXPECT_TRUE(connect_in(a));
  EXPECT_TRUE(connect_in(b));
  const std::string listening = "Listening to port " + std::to_string(port);
  EXPECT_NE(read_text(dir / "a.log").find(listening), std::string::npos)
      << read_text(dir / "a.log");
  EXPECT_NE(read_text(dir / "b.log").find(listening), std::string::npos)
      << read_text(dir / "b.log");
  // On the host, the port is the test's: the connection is accepted by the test's listener.
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  const sockaddr_in to = loopback(port);
  ASSERT_EQ(::connect(fd, reinterpret_cast<const sockaddr*>(&to), sizeof to), 0);
  const int accepted = ::accept4(host, nullptr, nullptr, SOCK_CLOEXEC);
  EXPECT_GE(accepted, 0) << "the host's connection did not reach the host's listener";
  if (accepted >= 0) ::close(accepted);
  ::close(fd);
  ::close(host);
  a.stop();
  b.stop();
  fs::remove_all(dir);
}

// The processes whose command line holds `marker` (a daemon a program started, say).
std::vector<pid_t> processes_with(const std::string& marker) {
  std::vector<pid_t> found;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string cmdline = read_text(entry.path() / "cmdline");
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    if (cmdline.find(marker) != std::string::npos) found.push_back(std::stoi(name));
  }
  return found;
}

// Waits up to `timeout` for `done()`.
template <class Done>
bool eventually(const Done& done, std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

// A command that starts two daemons (a new session, a double fork), each marked with `tag`
// in its command line, then goes on running as the planner would.
std::string daemonising(const std::string& tag) {
  return "setsid sleep 777." + tag + " & (sleep 778." + tag + " &); exec sleep 30";
}

// Only standard input, output and error reach the program: not a file the parent holds open
// without close-on-exec (as a bench's results file is).
TEST(PlannerProcessTest, OnlyStandardInputOutputAndErrorReachTheProgram) {
  const fs::path dir = fs::temp_directory_path() / ("overtake-fds-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream held(dir / "results.jsonl");  // open, inheritable
  for (const bool isolated : {false, true}) {
    if (isolated && !sandbox::private_network_available()) continue;
    sandbox::PlannerProcessOptions o;
    o.command = "exec ls -l /proc/self/fd";
    o.log = dir / "fds.log";
    o.isolated = isolated;
    sandbox::PlannerProcess p(o);
    ASSERT_TRUE(eventually([&] { return !p.ended().empty(); }, std::chrono::seconds(10)));
    p.stop();
    const std::string text = read_text(o.log);
    std::istringstream lines(text);
    std::string line;
    int descriptors = 0;
    while (std::getline(lines, line)) {
      const std::size_t arrow = line.find(" -> ");
      if (arrow == std::string::npos) continue;
      ++descriptors;
      const std::string target = line.substr(arrow + 4);
      const bool allowed = target == "/dev/null" || target.rfind("pipe:", 0) == 0 ||
                           target.find("/fd") != std::string::npos;  // ls's own listing
      EXPECT_TRUE(allowed) << "isolated " << isolated << ": " << line;
    }
    EXPECT_EQ(descriptors, 4) << text;  // 0, 1, 2 and the folder ls reads
    EXPECT_EQ(text.find("results.jsonl"), std::string::npos) << text;
  }
  fs::remove_all(dir);
}

// What a program starts, daemons included, ends with its run: after a normal stop, and after
// the process that started it is killed with SIGKILL (no destructor, no clean-up of its own).
// Both ways of holding the processes together: a PID namespace, and the subreaper used where
// namespaces cannot be had.
TEST(PlannerProcessTest, WhatAProgramStartsEndsWithItsRunEvenWhenOvertakeIsKilled) {
  const fs::path dir =
      fs::temp_directory_path() / ("overtake-daemons-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  for (const bool namespaces : {true, false}) {
    if (namespaces && !sandbox::private_network_available()) continue;
    SCOPED_TRACE(namespaces ? "PID namespace" : "subreaper");
    const std::string tag = std::to_string(::getpid()) + (namespaces ? "1" : "2");
    sandbox::PlannerProcessOptions o;
    o.command = daemonising(tag);
    o.log = dir / "daemons.log";
    o.isolated = false;
    o.namespaces = namespaces;
    {
      sandbox::PlannerProcess p(o);
      EXPECT_EQ(p.containment(),
                namespaces ? sandbox::Containment::pid_namespace : sandbox::Containment::subreaper);
      ASSERT_TRUE(
          eventually([&] { return processes_with(tag).size() == 2; }, std::chrono::seconds(10)));
      p.stop(0.2);
    }
    EXPECT_TRUE(eventually([&] { return processes_with(tag).empty(); }, std::chrono::seconds(3)))
        << processes_with(tag).size() << " left after a normal stop";

    // The same in a child process that is killed while the program runs.
    const std::string killed_tag = tag + "9";
    o.command = daemonising(killed_tag);
    const pid_t child = ::fork();
    if (child == 0) {
      sandbox::PlannerProcess p(o);
      ::pause();
      _exit(0);
    }
    ASSERT_GT(child, 0);
    EXPECT_TRUE(eventually([&] { return processes_with(killed_tag).size() == 2; },
                           std::chrono::seconds(10)));
    ::kill(child, SIGKILL);
    ::waitpid(child, nullptr, 0);
    EXPECT_TRUE(
        eventually([&] { return processes_with(killed_tag).empty(); }, std::chrono::seconds(3)))
        << processes_with(killed_tag).size() << " left after SIGKILL of their starter";
    for (const pid_t left : processes_with(killed_tag)) ::kill(left, SIGKILL);
  }
  fs::remove_all(dir);
}

// A process that ignores SIGCHLD (its children are reaped by the kernel, so waitpid cannot
// tell how they ended) still learns how the program ended, and stops it promptly.
TEST(PlannerProcessTest, AProcessThatIgnoresSigchldStillStopsItsProgram) {
  const fs::path log =
      fs::temp_directory_path() / ("overtake-sigchld-" + std::to_string(::getpid()) + ".log");
  struct sigaction ignore {
  }, old{};
  ignore.sa_handler = SIG_IGN;
  ::sigaction(SIGCHLD, &ignore, &old);
  {
    sandbox::PlannerProcessOptions o;
    o.command = "exit 7";
    o.log = log;
    o.isolated = false;
    sandbox::PlannerProcess p(o);
    EXPECT_TRUE(eventually([&] { return !p.ended().empty(); }, std::chrono::seconds(5)));
    EXPECT_EQ(p.ended(), "exited with status 7");
    const auto t0 = std::chrono::steady_clock::now();
    p.stop();
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(2));
  }
  ::sigaction(SIGCHLD, &old, nullptr);
  fs::remove(log);
}

// The program runs as the user who runs overtake, not as root of its user namespace. (As
// root, the test runs overtake as the user nobody, to go through the user namespace.)
TEST_F(PlannerProgramTest, TheProgramRunsAsTheUserNotAsRoot) {
  if (!sandbox::private_network_available()) GTEST_SKIP() << "no namespaces on this machine";
  std::vector<std::string> prefix;
  std::string uid = std::to_string(::getuid());
  if (::getuid() == 0) {
    if (!fs::exists("/usr/bin/setpriv")) GTEST_SKIP() << "no setpriv to run as another user";
    prefix = {"/usr/bin/setpriv", "--reuid=65534", "--regid=65534", "--clear-groups"};
    uid = "65534";
    fs::permissions(root_, fs::perms::all);
  }
  const fs::path log = root_ / "planner.log";
  std::vector<std::string> args = prefix;
  args.push_back(test::overtake_binary().string());
  for (const std::string& a :
       {std::string("sim"), std::string("--planner-cmd"),
        "echo uid $(id -u) gid $(id -g); exec " + course_planner().string(),
        std::string("--minutes"), std::string("0.05"), std::string("--planner-log"), log.string(),
        std::string("--planner-network"), std::string("isolated"), std::string("--quiet")}) {
    args.push_back(a);
  }
  const pid_t pid = test::start_command(args, root_ / "stdout", root_ / "stderr");
  const auto status = test::exit_status(pid, std::chrono::seconds(120));
  const std::string text = read_text(log);
  if (status != 0 && read_text(root_ / "stderr").find("namespace") != std::string::npos)
    GTEST_SKIP() << "no user namespaces for this user: " << read_text(root_ / "stderr");
  ASSERT_EQ(status, 0) << read_text(root_ / "stderr");
  EXPECT_NE(text.find("uid " + uid + " gid " + uid), std::string::npos) << text;
}

// Ctrl-C while a program has not yet started listening stops at once, not after the start
// timeout.
TEST_F(PlannerProgramTest, CtrlCWhileAProgramStartsStopsAtOnce) {
  const pid_t pid = test::start_overtake(
      {"sim", "--planner-cmd", course_planner().string() + " --never-listen", "--connect-timeout",
       "60", "--minutes", "1", "--planner-log", (root_ / "planner.log").string()},
      root_ / "stdout", root_ / "stderr");
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const auto t0 = std::chrono::steady_clock::now();
  ::kill(pid, SIGINT);
  const auto status = test::exit_status(pid, std::chrono::seconds(10));
  const auto waited = std::chrono::steady_clock::now() - t0;
  EXPECT_EQ(status, 130) << read_text(root_ / "stderr");
  EXPECT_LT(waited, std::chrono::milliseconds(1500));
  EXPECT_NE(read_text(root_ / "stdout").find("stopped"), std::string::npos)
      << read_text(root_ / "stdout");
}

// A bench's open results file does not reach its programs, and a daemon a program starts
// does not outlive its run; a run whose program cannot even be started fails alone.
TEST_F(PlannerProgramTest, ABenchKeepsItsFilesAndEndsWhatItsProgramsStart) {
  const fs::path out = root_ / "bench";
  const std::string tag = "31" + std::to_string(::getpid());
  ASSERT_EQ(
      run({"bench", "--planner-cmd",
           "ls -l /proc/self/fd; setsid sleep 779." + tag + " & exec " + course_planner().string(),
           "--planner-name", "course", "--seeds", "1-2", "--minutes", "0.2", "--traffic", "calm",
           "--jobs", "2", "--out", out.string(), "--quiet"}),
      0)
      << err_;
  const auto rows = read_rows(out / "runs.jsonl");
  ASSERT_EQ(rows.size(), 2u);
  for (const json& r : rows) EXPECT_EQ(r["end"], "completed") << r["ended_early"];
  for (const char* log : {"course-calm-seed1.log", "course-calm-seed2.log"}) {
    const std::string text = read_text(out / "logs" / log);
    EXPECT_NE(text.find("/dev/null"), std::string::npos) << text;
    EXPECT_EQ(text.find("runs.jsonl"), std::string::npos) << text;
    EXPECT_EQ(text.find("socket:"), std::string::npos) << text;
  }
  EXPECT_TRUE(
      eventually([&] { return processes_with("779." + tag).empty(); }, std::chrono::seconds(3)));
}

// A program that cannot even be started (here its log cannot be written) fails its own run,
// and the bench goes on with the others. (--force: a `logs` that is not a bench's folder would
// otherwise stop the bench before it starts.)
TEST_F(PlannerProgramTest, AProgramThatCannotBeStartedFailsItsRunOnly) {
  const fs::path out = root_ / "bench";
  fs::create_directories(out);
  std::ofstream(out / "logs") << "a file where the logs' folder would be\n";
  ASSERT_EQ(run({"bench", "--planner-cmd", course_planner().string(), "--planner-name", "course",
                 "--policies", "walkthrough", "--seeds", "1", "--minutes", "0.1", "--traffic",
                 "calm", "--out", out.string(), "--quiet", "--force"}),
            0)
      << err_;
  std::map<std::string, json> by;
  for (const json& r : read_rows(out / "runs.jsonl")) by[r["config"]["policy"]] = r;
  ASSERT_EQ(by.size(), 2u);
  EXPECT_EQ(by["walkthrough"]["end"], "completed");
  EXPECT_EQ(by["course"]["end"], "planner_failed");
  EXPECT_NE(by["course"]["ended_early"].get<std::string>().find(
                "cannot start the planner program: " + (out / "logs").string()),
            std::string::npos)
      << by["course"]["ended_early"];
}

// On the host's network, the scorecard says so: whatever listened on the port was trusted.
TEST_F(PlannerProgramTest, TheScorecardSaysWhenTheHostsNetworkWasUsed) {
  const int port = free_port();
  ASSERT_EQ(
      run({"sim", "--planner-cmd", course_planner().string() + " --port " + std::to_string(port),
           "--planner-port", std::to_string(port), "--planner-network", "host", "--minutes", "0.05",
           "--planner-log", (root_ / "planner.log").string()}),
      0)
      << err_;
  EXPECT_NE(out_.find("the host's: whatever listened on port " + std::to_string(port)),
            std::string::npos)
      << out_;
  ASSERT_EQ(run({"sim", "--planner-cmd", course_planner().string(), "--minutes", "0.05",
                 "--planner-log", (root_ / "planner.log").string()}),
            0)
      << err_;
  if (sandbox::private_network_available()) {
    EXPECT_EQ(out_.find("the host's"), std::string::npos) << out_;
  }
}

// The course-like program beside the built-in walkthrough it wraps, on 2 jobs: the program's
// reports equal the in-process ones, and each run's output is in its own log.
TEST_F(PlannerProgramTest, BenchRunsProgramsInParallelWithTheSameReportsAsInProcess) {
  const fs::path out = root_ / "bench";
  ASSERT_EQ(run({"bench", "--policies", "walkthrough", "--planner-cmd", course_planner().string(),
                 "--planner-name", "course", "--seeds", "1-3", "--minutes", "1", "--traffic",
                 "faithful", "--jobs", "2", "--out", out.string(), "--quiet"}),
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
                 p + " --crash-after 30",
                 "--planner-cmd",
                 p + " --hang-after 30",
                 "--planner-cmd",
                 p + " --never-listen",
                 "--planner-cmd",
                 p + " --exit-at-start",
                 "--planner-cmd",
                 p,
                 "--planner-name",
                 "crash",
                 "--planner-name",
                 "hang",
                 "--planner-name",
                 "silent",
                 "--planner-name",
                 "quits",
                 "--planner-name",
                 "good",
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
  const int port = free_port();
  ASSERT_EQ(run({"bench",
                 "--planner-cmd",
                 course_planner().string() + " --port " + std::to_string(port),
                 "--planner-name",
                 "course",
                 "--planner-port",
                 std::to_string(port),
                 "--planner-network",
                 "host",
                 "--seeds",
                 "1-2",
                 "--minutes",
                 "0.5",
                 "--traffic",
                 "calm",
                 "--jobs",
                 "2",
                 "--out",
                 out.string(),
                 "--quiet"}),
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
  ASSERT_EQ(
      run({"bench", "--planner-cmd", program.string() + " " + map, "--planner-name", "example",
           "--seeds", "1-2", "--minutes", "4", "--jobs", "2", "--out", out.string(), "--quiet"}),
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
