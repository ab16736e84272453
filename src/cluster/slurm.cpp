#include "overtake/cluster/slurm.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <nlohmann/json.hpp>

#include "command.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/shard.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/sandbox/planner_process.hpp"

namespace overtake::cluster {

using base::json_text;
using base::kExitFailure;
using base::kExitInterrupted;
using base::kExitOk;
using base::read_file;
using base::shell_quote;
using base::stderr_is_terminal;
using base::UsageError;
using base::write_file_atomic;
using command_detail::command_error;
using command_detail::CommandResult;
using command_detail::last_line;
using command_detail::run_command;
using command_detail::trimmed;
using planners::PlannerCatalog;
using run::read_json_file;
using sandbox::private_network_available;
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr int kMaxTasks = 10000;
constexpr int kMaxCpus = 256;
constexpr int kMaxRetries = 100;
constexpr double kMinPollS = 0.05;
constexpr double kMaxPollS = 3600.0;
/// A Slurm command that takes longer than this is stopped (the controller may be away).
constexpr double kCommandTimeoutS = 120.0;
constexpr const char* kStateFile = "state.json";
constexpr int kStateVersion = 1;

// ----- the array's state (OUT/slurm/state.json) --------------------------------------------

struct ArrayState {
  std::string command;
  int tasks = 0;
  std::size_t runs = 0;
  std::vector<std::string> args;
  /// attempts[i]: the array jobs task i+1 was submitted in, first to last.
  std::vector<std::vector<std::string>> attempts;
};

json state_json(const ArrayState& s) {
  return {{"version", kStateVersion}, {"command", s.command}, {"tasks", s.tasks},
          {"runs", s.runs},           {"args", s.args},       {"attempts", s.attempts}};
}

ArrayState read_state(const fs::path& file) {
  try {
    const json j = read_json_file(file);
    if (j.value("version", 0) != kStateVersion) throw std::runtime_error("another version");
    ArrayState s;
    s.command = j.at("command").get<std::string>();
    s.tasks = j.at("tasks").get<int>();
    s.runs = j.at("runs").get<std::size_t>();
    s.args = j.at("args").get<std::vector<std::string>>();
    s.attempts = j.at("attempts").get<std::vector<std::vector<std::string>>>();
    if (s.tasks < 1 || s.attempts.size() != static_cast<std::size_t>(s.tasks))
      throw std::runtime_error("the tasks do not match their attempts");
    return s;
  } catch (const std::exception& e) {
    throw UsageError("--resume: " + file.string() + " cannot be read (" + e.what() +
                     "); it is not the state of a Slurm array of this version");
  }
}

std::string script_name(const SlurmArray& a) {
  return a.command + ".sbatch";
}

fs::path log_path(const fs::path& out, int task, const std::string& job) {
  return slurm_dir(out) / "logs" / ("task-" + std::to_string(task) + ".job-" + job + ".log");
}

bool sbatch_line_safe(std::string_view s) {
  return s.find_first_of("\n\r\"") == std::string_view::npos;
}

std::string sbatch_value(std::string_view s) {
  if (s.find_first_of(" \t'") == std::string_view::npos) return std::string(s);
  return "\"" + std::string(s) + "\"";
}

std::string clock_text(double s) {
  char buf[32];
  const long t = std::lround(s);
  if (t >= 3600)
    std::snprintf(buf, sizeof buf, "%ldh%02ldm", t / 3600, (t / 60) % 60);
  else if (t >= 60)
    std::snprintf(buf, sizeof buf, "%ldm%02lds", t / 60, t % 60);
  else
    std::snprintf(buf, sizeof buf, "%lds", t);
  return buf;
}

// Whether a job in this state has ended for good (Slurm's base job states; anything else,
// PENDING, RUNNING, COMPLETING, SUSPENDED, REQUEUED, ..., may still run).
bool slurm_state_final(const std::string& state) {
  static const std::set<std::string> kFinal = {
      "COMPLETED", "FAILED",   "CANCELLED",     "TIMEOUT", "NODE_FAIL",   "PREEMPTED",
      "BOOT_FAIL", "DEADLINE", "OUT_OF_MEMORY", "REVOKED", "SPECIAL_EXIT"};
  return kFinal.count(state) > 0;
}

// ----- following the array -----------------------------------------------------------------

enum class TaskStatus { queued, done, gave_up };

class Follower {
 public:
  Follower(const SlurmArray& array, const SlurmOptions& options, ArrayState& state)
      : array_(array), options_(options), state_(state) {
    status_.assign(static_cast<std::size_t>(state.tasks), TaskStatus::queued);
    retried_.assign(static_cast<std::size_t>(state.tasks), 0);
    draw_ = !array.quiet && stderr_is_terminal();
  }

  // Submits the tasks (1-based); records the new job in the state.
  void submit(const std::vector<int>& tasks, bool whole_array) {
    std::vector<std::string> argv = {"sbatch", "--parsable"};
    if (!whole_array) {
      std::string list;
      for (int t : tasks) list += (list.empty() ? "" : ",") + std::to_string(t);
      argv.push_back("--array=" + list);
    }
    argv.push_back((slurm_dir(array_.out) / script_name(array_)).string());
    const CommandResult r = run_command(argv, kCommandTimeoutS);
    if (r.status != 0) {
      throw std::runtime_error("--slurm: sbatch refused the array: " + command_error(argv, r));
    }
    const std::string job = parse_sbatch_job_id(r.out);
    for (int t : tasks) state_.attempts[static_cast<std::size_t>(t - 1)].push_back(job);
    save();
  }

  void save() const {
    write_file_atomic(slurm_dir(array_.out) / kStateFile, json_text(state_json(state_), 2) + "\n");
  }

  // Looks at the queue once: tasks that left it are done, or submitted again, or given up.
  // Returns false when the queue could not be read (nothing is concluded then).
  bool look() {
    const std::vector<std::string> argv = {"squeue", "--noheader", "--array", "--me",
                                           "--format=%i %T"};
    const CommandResult r = run_command(argv, kCommandTimeoutS);
    if (r.status != 0) {
      const std::string why = command_error(argv, r);
      if (why != last_queue_error_)
        note("slurm: cannot read the queue (" + why + "); trying again");
      last_queue_error_ = why;
      return false;
    }
    last_queue_error_.clear();
    std::map<std::pair<std::string, int>, std::string> queued;
    for (const SlurmQueued& q : parse_squeue_tasks(r.out)) queued[{q.job, q.task}] = q.state;
    running_ = pending_ = 0;
    std::vector<int> again;
    for (int t = 1; t <= state_.tasks; ++t) {
      const auto i = static_cast<std::size_t>(t - 1);
      if (status_[i] != TaskStatus::queued) continue;
      const auto& attempts = state_.attempts[i];
      if (attempts.empty()) {  // never submitted (a state cut short): submit it
        again.push_back(t);
        continue;
      }
      const auto it = queued.find({attempts.back(), t});
      if (it != queued.end()) {
        if (it->second == "PENDING" || it->second == "CONFIGURING")
          ++pending_;
        else
          ++running_;
        continue;
      }
      ended(t, again);
    }
    if (!again.empty()) {
      submit(again, false);
      pending_ += static_cast<int>(again.size());
    }
    return true;
  }

  [[nodiscard]] std::vector<fs::path> shards() const {
    std::vector<fs::path> dirs;
    for (int t = 1; t <= state_.tasks; ++t) dirs.push_back(slurm_shard_dir(array_.out, t));
    return dirs;
  }

  [[nodiscard]] int count(TaskStatus s) const {
    return static_cast<int>(std::count(status_.begin(), status_.end(), s));
  }
  [[nodiscard]] bool all_done() const { return count(TaskStatus::done) == state_.tasks; }
  [[nodiscard]] bool settled() const { return count(TaskStatus::queued) == 0; }
  [[nodiscard]] const std::vector<std::string>& failures() const { return failures_; }
  [[nodiscard]] int resubmitted() const { return resubmitted_; }

  // Job ids of the tasks still queued (for scancel).
  [[nodiscard]] std::vector<std::string> live_jobs() const {
    std::set<std::string> jobs;
    for (int t = 1; t <= state_.tasks; ++t) {
      const auto i = static_cast<std::size_t>(t - 1);
      if (status_[i] == TaskStatus::queued && !state_.attempts[i].empty())
        jobs.insert(state_.attempts[i].back());
    }
    return {jobs.begin(), jobs.end()};
  }

  void progress(double wall_s) {
    if (array_.quiet) return;
    const std::string written = array_.progress ? array_.progress(shards()) : "";
    const int failed = count(TaskStatus::gave_up);
    const std::string failed_text = failed > 0 ? ", " + std::to_string(failed) + " failed" : "";
    char line[512];
    std::snprintf(line, sizeof line, "slurm: %d/%d tasks done, %d running, %d pending%s; %s; %s",
                  count(TaskStatus::done), state_.tasks, running_, pending_, failed_text.c_str(),
                  written.c_str(), clock_text(wall_s).c_str());
    if (draw_) {
      std::fprintf(stderr, "\r%s   ", line);
      std::fflush(stderr);
      return;
    }
    // Not a terminal (a log): a line when a task changed state, or at most once a minute
    // when only runs were written.
    std::string key(line);
    key = key.substr(0, key.find(';'));
    if (key != last_progress_ || (written != last_written_ && wall_s >= last_line_s_ + 60.0)) {
      std::fprintf(stderr, "%s\n", line);
      last_progress_ = key;
      last_written_ = written;
      last_line_s_ = wall_s;
    }
  }

  void end_progress() const {
    if (draw_) std::fprintf(stderr, "\n");
  }

 private:
  void note(const std::string& text) const {
    if (array_.quiet) return;
    if (draw_) std::fprintf(stderr, "\r\033[K");
    std::fprintf(stderr, "%s\n", text.c_str());
  }

  // Task t's last attempt left the queue: finished, or to be submitted again.
  void ended(int t, std::vector<int>& again) {
    const auto i = static_cast<std::size_t>(t - 1);
    const std::string& job = state_.attempts[i].back();
    const std::string id = job + "_" + std::to_string(t);
    const CommandResult r = run_command({"scontrol", "show", "job", id}, kCommandTimeoutS);
    SlurmJobEnd end;
    if (r.status == 0) end = parse_scontrol_job(r.out);
    if (!end.state.empty() && !slurm_state_final(end.state)) {
      ++running_;  // not listed yet, or requeued: Slurm still has it
      return;
    }
    const SlurmShardState shard = array_.shard_state(slurm_shard_dir(array_.out, t), t);
    if (shard.finished && (end.state.empty() || end.state == "COMPLETED")) {
      status_[i] = TaskStatus::done;
      return;
    }
    std::string why = end.state.empty() ? "left the queue (Slurm no longer knows how it ended)"
                                        : "ended " + end.state;
    if (!end.exit_code.empty() && end.exit_code != "0:0") why += " (exit " + end.exit_code + ")";
    if (!end.reason.empty()) why += " [" + end.reason + "]";
    if (!shard.so_far.empty()) why += " with " + shard.so_far;
    std::string tail;
    try {
      tail = last_line(read_file(log_path(array_.out, t, job)));
    } catch (const std::exception&) {
    }
    if (!tail.empty()) why += ": " + tail;
    if (retried_[i] < options_.retries) {
      ++retried_[i];
      note("slurm: task " + std::to_string(t) + " (job " + id + ") " + why +
           "; submitting it again (retry " + std::to_string(retried_[i]) + " of " +
           std::to_string(options_.retries) + ")");
      again.push_back(t);
      ++resubmitted_;
      return;
    }
    status_[i] = TaskStatus::gave_up;
    failures_.push_back("task " + std::to_string(t) + " (job " + id + ") " + why);
    note("slurm: task " + std::to_string(t) + " (job " + id + ") " + why + "; giving up on it");
  }

  const SlurmArray& array_;
  const SlurmOptions& options_;
  ArrayState& state_;
  std::vector<TaskStatus> status_;
  std::vector<int> retried_;  ///< submissions again, by this invocation
  std::vector<std::string> failures_;
  std::string last_queue_error_;
  std::string last_progress_;
  std::string last_written_;
  double last_line_s_ = 0.0;
  int running_ = 0;
  int pending_ = 0;
  int resubmitted_ = 0;
  bool draw_ = false;
};

std::string jobs_text(const std::vector<std::string>& jobs) {
  std::string s;
  for (const auto& j : jobs) s += (s.empty() ? "" : " ") + j;
  return s;
}

}  // namespace

// ----- the pieces --------------------------------------------------------------------------

SlurmArray slurm_array_here(const std::string& command, const fs::path& out) {
  SlurmArray a;
  a.command = command;
  std::error_code ec;
  a.workdir = fs::current_path();
  a.out = fs::absolute(out).lexically_normal();
  a.binary = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("--slurm: cannot find this binary (" + ec.message() + ")");
  return a;
}

fs::path slurm_dir(const fs::path& out) {
  return out / "slurm";
}

fs::path slurm_shard_dir(const fs::path& out, int task) {
  return out / "shards" / ("shard-" + std::to_string(task));
}

std::size_t slurm_shard_runs(std::size_t runs, int tasks, int task) {
  return batch::Shard{task, tasks}.size_of(runs);
}

void check_programs_for_slurm(const PlannerCatalog& planners, const std::string& network) {
  if (!planners.has_programs()) return;
  // What the nodes allow, whatever the runs ask for: checked as automatic unless isolated.
  const sandbox::NetworkCheck check =
      sandbox::check_planner_network(network == "isolated" ? sandbox::PlannerNetwork::isolated
                                                           : sandbox::PlannerNetwork::automatic);
  if (check.own_network) return;
  const std::string& why = check.why;
  if (check.refused) {
    throw UsageError(
        "--planner-network isolated: this machine cannot give each run its own network (" + why +
        "); on nodes like it every task would fail. Use --planner-network auto (the runs of a "
        "task then take turns on the node's network) or a machine that allows namespaces");
  }
  std::fprintf(stderr,
               "slurm: this machine cannot give each run its own network (%s); on nodes like it, "
               "a task runs its planner programs one at a time on the node's network\n",
               why.c_str());
}

void validate_slurm_options(const SlurmOptions& o, std::size_t runs) {
  if (o.tasks < 1 || o.tasks > kMaxTasks) {
    throw UsageError("--slurm: the number of tasks must be between 1 and " +
                     std::to_string(kMaxTasks) + " (got " + std::to_string(o.tasks) + ")");
  }
  if (static_cast<std::size_t>(o.tasks) > runs) {
    throw UsageError("--slurm: " + std::to_string(o.tasks) + " tasks for " + std::to_string(runs) +
                     " runs; a task needs at least one run");
  }
  if (o.cpus_per_task < 1 || o.cpus_per_task > kMaxCpus) {
    throw UsageError("--slurm-cpus must be between 1 and " + std::to_string(kMaxCpus) + " (got " +
                     std::to_string(o.cpus_per_task) + ")");
  }
  if (o.retries < 0 || o.retries > kMaxRetries) {
    throw UsageError("--slurm-retries must be between 0 and " + std::to_string(kMaxRetries) +
                     " (got " + std::to_string(o.retries) + ")");
  }
  if (!(o.poll_s >= kMinPollS && o.poll_s <= kMaxPollS)) {
    std::ostringstream os;
    os << "--slurm-poll must be between " << kMinPollS << " and " << kMaxPollS << " seconds (got "
       << o.poll_s << ")";
    throw UsageError(os.str());
  }
  const auto plain = [](const std::string& flag, const std::string& v) {
    if (!sbatch_line_safe(v) || v.find_first_of(" \t") != std::string::npos) {
      throw UsageError(flag + ": '" + v + "' may not hold spaces, quotes or line breaks");
    }
  };
  plain("--slurm-partition", o.partition);
  plain("--slurm-time", o.time_limit);
  for (const auto& opt : o.sbatch_options) {
    if (opt.empty() || opt[0] != '-' || !sbatch_line_safe(opt)) {
      throw UsageError("--slurm-opt: '" + opt +
                       "' is not an sbatch option (one option such as --account=NAME or "
                       "--mem=2G, without quotes or line breaks)");
    }
    for (const char* ours : {"--array", "--output", "--chdir", "--job-name", "--cpus-per-task",
                             "--partition", "--time", "--wrap", "--parsable"}) {
      const std::string_view name(ours);
      if (opt.rfind(name, 0) == 0 && (opt.size() == name.size() || opt[name.size()] == '=')) {
        throw UsageError("--slurm-opt: " + std::string(name) +
                         " is overtake's to set (the array, its logs and folder, its name); "
                         "--slurm, --slurm-cpus, --slurm-partition and --slurm-time set the rest");
      }
    }
  }
}

std::string slurm_batch_script(const SlurmArray& a, const SlurmOptions& o) {
  const std::string n = std::to_string(o.tasks);
  const std::string cpus = std::to_string(o.cpus_per_task);
  std::ostringstream s;
  s << "#!/bin/sh\n"
    << "# overtake " << a.command << " as a Slurm job array: task I runs shard I of " << n
    << " into shards/shard-I.\n"
    << "# Written by `overtake " << a.command << " --slurm " << n
    << "`, which follows the tasks, submits again those that end\n"
    << "# unfinished and merges the shards (docs/cluster.md).\n"
    << "#SBATCH --job-name=overtake-" << a.command << "\n"
    << "#SBATCH --array=1-" << n << "\n"
    << "#SBATCH --cpus-per-task=" << cpus << "\n"
    << "#SBATCH --chdir=" << sbatch_value(a.workdir.string()) << "\n"
    << "#SBATCH --output="
    << sbatch_value((slurm_dir(a.out) / "logs" / "task-%a.job-%A.log").string()) << "\n";
  if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
  if (!o.time_limit.empty()) s << "#SBATCH --time=" << o.time_limit << "\n";
  for (const auto& opt : o.sbatch_options) s << "#SBATCH " << opt << "\n";
  s << "exec " << shell_quote(a.binary.string()) << " " << a.command;
  for (const auto& arg : a.args) s << " " << shell_quote(arg);
  s << " --shard=\"$SLURM_ARRAY_TASK_ID\"/" << n
    << " --out=" << shell_quote((a.out / "shards" / "shard-").string())
    << "\"$SLURM_ARRAY_TASK_ID\""
    << " --jobs=" << cpus;
  for (const auto& f : a.task_flags) s << " " << shell_quote(f);
  s << "\n";
  return s.str();
}

std::string parse_sbatch_job_id(std::string_view answer) {
  const std::string line = trimmed(answer.substr(0, answer.find('\n')));
  const std::string id = line.substr(0, line.find(';'));
  if (id.empty() || !std::all_of(id.begin(), id.end(), [](char c) {
        return std::isdigit(static_cast<unsigned char>(c)) != 0;
      })) {
    throw std::runtime_error("--slurm: sbatch answered '" + trimmed(answer) +
                             "', which holds no job id");
  }
  return id;
}

std::vector<SlurmQueued> parse_squeue_tasks(std::string_view listing) {
  std::vector<SlurmQueued> out;
  std::istringstream in{std::string(listing)};
  std::string id, state;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    if (!(words >> id >> state)) continue;
    const auto us = id.find('_');
    if (us == std::string::npos || us == 0) continue;
    const std::string job = id.substr(0, us);
    const std::string task = id.substr(us + 1);
    const auto digits = [](const std::string& s) {
      return !s.empty() && s.size() <= 9 && std::all_of(s.begin(), s.end(), [](char c) {
        return std::isdigit(static_cast<unsigned char>(c)) != 0;
      });
    };
    if (!digits(job) || !digits(task)) continue;  // "123_[5-8]": a range, not one task
    out.push_back({job, std::stoi(task), state});
  }
  return out;
}

SlurmJobEnd parse_scontrol_job(std::string_view text) {
  SlurmJobEnd end;
  std::istringstream in{std::string(text)};
  std::string word;
  while (in >> word) {
    const auto eq = word.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = word.substr(0, eq);
    const std::string value = word.substr(eq + 1);
    if (key == "JobState" && end.state.empty()) end.state = value;
    if (key == "ExitCode" && end.exit_code.empty()) end.exit_code = value;
    if (key == "Reason" && end.reason.empty() && value != "None") end.reason = value;
  }
  return end;
}

// ----- the whole ---------------------------------------------------------------------------

namespace {

// The array's state: the one OUT/slurm/state.json holds (--resume), or a new one.
ArrayState array_state(const SlurmArray& a, const SlurmOptions& options, const fs::path& state_file,
                       bool taken_up) {
  ArrayState state;
  if (taken_up) {
    if (!a.resume) {
      throw UsageError("--out: " + a.out.string() + " holds a Slurm " + a.command + " already (" +
                       state_file.string() +
                       "); --resume follows it, submits again what did not finish and merges");
    }
    state = read_state(state_file);
    if (state.command != a.command || state.args != a.args || state.tasks != options.tasks ||
        state.runs != a.runs) {
      throw UsageError("--resume: " + a.out.string() + " holds a different Slurm " + state.command +
                       " (the flags or the number of tasks differ); " + "use another --out");
    }
    return state;
  }
  if (fs::exists(a.out / "shards")) {
    throw UsageError("--out: " + a.out.string() +
                     " holds shards but no Slurm state; choose another --out");
  }
  state.command = a.command;
  state.tasks = options.tasks;
  state.runs = a.runs;
  state.args = a.args;
  state.attempts.assign(static_cast<std::size_t>(options.tasks), {});
  return state;
}

// Writes the batch script (and the folder of the tasks' logs); returns its path.
fs::path write_batch_script(const SlurmArray& a, const SlurmOptions& options, const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir / "logs", ec);
  if (ec) {
    throw std::runtime_error(dir.string() + ": cannot create the Slurm folder (" + ec.message() +
                             ")");
  }
  const fs::path script = dir / script_name(a);
  write_file_atomic(script, slurm_batch_script(a, options));
  fs::permissions(script, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add, ec);
  return script;
}

// Follows the tasks until every one is done or given up (true), or the user stops (false:
// the tasks go on in Slurm).
bool follow_tasks(Follower& follower, const SlurmArray& a, const SlurmOptions& options,
                  const std::atomic<bool>* stop, const std::function<double()>& wall) {
  for (;;) {
    (void)follower.look();
    follower.progress(wall());
    if (follower.settled()) return true;
    const auto until =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(options.poll_s);
    while (std::chrono::steady_clock::now() < until) {
      if (stop && stop->load()) {
        follower.end_progress();
        std::cerr << a.command << ": stopped following; the tasks go on in Slurm (jobs "
                  << jobs_text(follower.live_jobs())
                  << "): the same command with --resume follows them again and merges, "
                     "scancel "
                  << jobs_text(follower.live_jobs()) << " cancels them\n";
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
}

}  // namespace

int run_slurm_array(const SlurmArray& a, const SlurmOptions& options,
                    const std::atomic<bool>* stop) {
  validate_slurm_options(options, a.runs);
  const fs::path dir = slurm_dir(a.out);
  const fs::path state_file = dir / kStateFile;
  const bool taken_up = fs::exists(state_file);
  ArrayState state = array_state(a, options, state_file, taken_up);
  const fs::path script = write_batch_script(a, options, dir);

  Follower follower(a, options, state);
  const auto wall0 = std::chrono::steady_clock::now();
  const std::function<double()> wall = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  };
  if (!taken_up) {
    std::vector<int> all;
    for (int t = 1; t <= options.tasks; ++t) all.push_back(t);
    follower.submit(all, true);
    if (!a.quiet) {
      std::fprintf(stderr, "slurm: submitted %d tasks as job %s (script %s)\n", options.tasks,
                   state.attempts.front().back().c_str(), script.c_str());
    }
  }
  if (options.submit_only) {
    if (taken_up) (void)follower.look();  // submits again what ended unfinished
    if (!taken_up || !follower.all_done()) {
      std::cout << "submitted: jobs " << jobs_text(follower.live_jobs()) << "\n"
                << "follow them (waits, submits again what fails, merges): the same command "
                   "with --resume instead of --slurm-submit-only\n"
                << "or, once every task is done: overtake " << a.command << " merge "
                << (a.out / "shards").string() << "/shard-* --out " << a.out.string() << "\n";
      return kExitOk;
    }
    return a.merge(follower.shards(), wall(), follower.resubmitted());
  }
  if (!follow_tasks(follower, a, options, stop, wall)) return kExitInterrupted;
  follower.end_progress();
  if (!follower.all_done()) {
    std::cerr << a.command << ": " << follower.failures().size() << " Slurm task"
              << (follower.failures().size() == 1 ? "" : "s") << " did not finish:\n";
    for (const auto& f : follower.failures()) std::cerr << "  " << f << "\n";
    std::cerr << "the finished shards are kept in " << (a.out / "shards").string()
              << "; the same command with --resume submits the rest again (logs in "
              << (dir / "logs").string() << ")\n";
    return kExitFailure;
  }
  return a.merge(follower.shards(), wall(), follower.resubmitted());
}

}  // namespace overtake::cluster
