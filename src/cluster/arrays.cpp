#include "overtake/cluster/arrays.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/bench_page.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/config.hpp"

namespace overtake::cluster {

using base::kExitInterrupted;
using base::kExitOk;
using base::UsageError;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// Complete lines in a file (runs written to a runs.jsonl): a cheap count for the progress line.
std::size_t lines_in(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::size_t n = 0;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    n += static_cast<std::size_t>(std::count(buf, buf + in.gcount(), '\n'));
  }
  return n;
}

// A shard's hunt.json, or null while there is none that can be read.
json hunt_report(const fs::path& shard) {
  try {
    return run::read_json_file(shard / "hunt.json");
  } catch (const std::exception&) {
    return nullptr;
  }
}

}  // namespace

SlurmArray bench_array(const batch::BenchSpec& spec, int tasks, std::vector<std::string> args,
                       BenchMerged merged) {
  SlurmArray a = slurm_array_here("bench", spec.out);
  if (fs::exists(a.out / batch::kBenchRunsFile) || fs::exists(a.out / batch::kBenchManifestFile)) {
    throw UsageError("--out: " + a.out.string() +
                     " already holds bench results (merged, or a local bench); choose another "
                     "--out");
  }
  // The shards merge into --out at the end: what the merge would refuse is refused now.
  batch::check_bench_out(a.out, false, "--out: ", "move it away, or choose another --out");
  a.args = std::move(args);
  a.task_flags = {"--resume", "--quiet"};
  a.runs = batch::bench_combinations(spec).size();
  a.resume = spec.resume;
  const std::size_t runs = a.runs;
  const auto slice = [runs, tasks](int task) {
    return tasks > 0 ? slurm_shard_runs(runs, tasks, task) : 0;
  };
  a.shard_state = [slice](const fs::path& shard, int task) {
    SlurmShardState st;
    const std::size_t want = slice(task);
    try {
      const std::size_t have = batch::load_bench_runs(shard).size();
      st.finished = have == want && fs::exists(shard / batch::kBenchSummaryJsonFile);
      st.so_far = std::to_string(have) + " of " + std::to_string(want) + " runs";
    } catch (const std::exception& e) {  // not finished: the merge names what is wrong
      st.so_far = e.what();
    }
    return st;
  };
  a.progress = [slice, runs](const std::vector<fs::path>& shards) {
    std::size_t have = 0;
    for (std::size_t i = 0; i < shards.size(); ++i) {
      have += std::min(lines_in(shards[i] / batch::kBenchRunsFile), slice(static_cast<int>(i) + 1));
    }
    return std::to_string(have) + "/" + std::to_string(runs) + " runs";
  };
  a.merge = [out = a.out, merged = std::move(merged)](const std::vector<fs::path>& shards,
                                                      double wall_s, int resubmitted) {
    return merged(batch::merge_bench(shards, out), out, shards.size(), wall_s, resubmitted);
  };
  return a;
}

SlurmArray hunt_array(const batch::HuntSpec& spec, std::vector<std::string> args, bool resume,
                      bool quiet) {
  SlurmArray a = slurm_array_here("hunt", spec.out);
  if (fs::exists(a.out / "hunt.json")) {
    throw UsageError("--out: " + a.out.string() +
                     " already holds a hunt (merged, or a local hunt); choose another --out");
  }
  // The shards merge into --out at the end: what the merge would refuse is refused now.
  batch::check_hunt_out(a.out, false, "--out: ", "move it away, or choose another --out");
  a.args = std::move(args);
  // A task submitted again starts its shard over, in the array's own folder.
  a.task_flags = {"--force", "--quiet"};
  a.runs = batch::hunt_max_runs(spec);
  a.resume = resume;
  a.quiet = quiet;
  a.shard_state = [](const fs::path& shard, int) {
    SlurmShardState st;
    const json j = hunt_report(shard);
    if (j.is_object()) {
      st.finished = j.contains("shard") && j["shard"].value("finished", false);
      st.so_far = std::to_string(j.value("runs", 0)) + " runs and " +
                  std::to_string(j.value("failures", json::array()).size()) + " failures";
    }
    return st;
  };
  a.progress = [](const std::vector<fs::path>& shards) {
    std::size_t runs = 0, failures = 0;
    for (const auto& shard : shards) {
      const json j = hunt_report(shard);
      if (!j.is_object()) continue;
      runs += j.value("runs", std::size_t{0});
      failures += j.value("failures", json::array()).size();
    }
    return std::to_string(runs) + " runs, " + std::to_string(failures) + " failures found";
  };
  a.merge = [out = a.out, quiet](const std::vector<fs::path>& shards, double wall_s,
                                 int resubmitted) {
    (void)batch::merge_hunt(shards, out);
    if (!quiet) {
      std::cout << base::read_file(out / "hunt.md");
      std::printf("%zu Slurm tasks (%d submitted again) in %.1f s\n", shards.size(), resubmitted,
                  wall_s);
      std::cout << "written: " << out.string() << "/{hunt.md,hunt.json,replays,scenarios}\n";
    }
    return kExitOk;
  };
  return a;
}

SlurmArray risk_array(const batch::RiskSpec& spec, int tasks, std::vector<std::string> args,
                      const fs::path& json_out, bool quiet, const std::atomic<bool>* stop) {
  SlurmArray a = slurm_array_here("risk", spec.out);
  if (fs::exists(a.out / "risk-spec.json") || fs::exists(a.out / "runs.jsonl")) {
    throw UsageError("--out: " + a.out.string() +
                     " already holds an estimate (merged, or a local one); choose another --out");
  }
  a.args = std::move(args);
  a.task_flags = {"--resume", "--quiet"};
  a.runs = batch::risk_runs_planned(spec);
  a.resume = spec.resume;
  a.quiet = quiet;
  const std::size_t runs = a.runs;
  a.shard_state = [runs, tasks](const fs::path& shard, int task) {
    SlurmShardState s;
    const std::size_t want = slurm_shard_runs(runs, tasks, task);
    try {
      const json j = run::read_json_file(shard / "risk.json");
      s.finished = j.contains("shard") && j["shard"].value("finished", false);
    } catch (const std::exception&) {  // not finished: the merge names what is wrong
    }
    // The runs its runs.jsonl holds (a last line cut short counts, as it is redone).
    s.so_far =
        std::to_string(lines_in(shard / "runs.jsonl")) + " of " + std::to_string(want) + " runs";
    return s;
  };
  a.progress = [runs](const std::vector<fs::path>& shards) {
    std::size_t have = 0;
    for (const auto& shard : shards) have += lines_in(shard / "runs.jsonl");
    return std::to_string(have) + "/" + std::to_string(runs) + " runs";
  };
  batch::RiskSpec merged = spec;
  merged.out = a.out;
  merged.resume = false;
  a.merge = [merged, json_out, quiet, stop](const std::vector<fs::path>& shards, double wall_s,
                                            int resubmitted) {
    const batch::RiskOutcome o = batch::merge_risk(merged, shards, stop);
    return batch::report_risk(merged, o, json_out, quiet,
                              std::to_string(shards.size()) + " Slurm tasks (" +
                                  std::to_string(resubmitted) + " submitted again) in " +
                                  base::fixed_text(wall_s, 1) + " s\n");
  };
  return a;
}

std::vector<std::string> bench_task_flags(const batch::BenchSpec& b,
                                          const std::vector<std::string>& planner_flags) {
  std::vector<std::string> seeds;
  for (const std::uint64_t s : b.seeds) seeds.push_back(std::to_string(s));
  std::vector<std::string> args = {"--policies=" + base::join_list(b.policies, ","),
                                   "--seeds=" + base::join_list(seeds, ","),
                                   "--traffic=" + base::join_list(b.traffic, ","),
                                   "--minutes=" + base::shortest_text(b.minutes)};
  if (b.map) args.push_back("--map=" + fs::absolute(*b.map).string());
  if (b.config) args.push_back("--config=" + fs::absolute(*b.config).string());
  for (const std::string& name : b.planners->added_names()) {
    const planners::PlannerEntry& e = *b.planners->find(name);
    switch (e.kind) {
      case planners::PlannerKind::program:
        args.push_back(std::string(planners::flag_of(e.kind)) + "=" + e.program->command);
        args.push_back("--planner-name=" + e.name);
        break;
      case planners::PlannerKind::python:
      case planners::PlannerKind::plugin:
        // The task's working directory is this one (sbatch --chdir): the source as given.
        args.push_back(std::string(planners::flag_of(e.kind)) + "=" + e.name + "=" + e.source);
        if (!e.params.empty()) {
          args.push_back("--planner-params=" + e.name + "=" + json(e.params).dump());
        }
        break;
      case planners::PlannerKind::builtin:
        break;
    }
  }
  args.insert(args.end(), planner_flags.begin(), planner_flags.end());
  return args;
}

std::function<bool(const batch::BenchSpec&, const std::atomic<bool>*)> tune_bench_runner(
    const SlurmOptions& options, std::vector<std::string> planner_flags) {
  return [options, planner_flags = std::move(planner_flags)](const batch::BenchSpec& b,
                                                             const std::atomic<bool>* stop) {
    if (fs::exists(b.out / batch::kBenchRunsFile) &&
        fs::exists(b.out / batch::kBenchSummaryJsonFile))
      return false;
    std::fprintf(stderr, "tune: the bench %s as a Slurm array of %d tasks\n", b.out.c_str(),
                 options.tasks);
    batch::BenchSpec spec = b;
    spec.resume = fs::exists(slurm_dir(b.out) / "state.json");
    SlurmArray array = bench_array(spec, options.tasks, bench_task_flags(b, planner_flags),
                                   [](const batch::BenchOutcome&, const fs::path&, std::size_t,
                                      double, int) { return kExitOk; });
    array.quiet = true;
    const int status = run_slurm_array(array, options, stop);
    if (status == kExitInterrupted) return true;
    if (status != kExitOk) {
      throw std::runtime_error("the bench " + b.out.string() + " did not finish on Slurm (exit " +
                               std::to_string(status) + "); its tasks' logs are in " +
                               slurm_dir(b.out).string() +
                               ", and --resume takes the search up again");
    }
    return false;
  };
}

}  // namespace overtake::cluster
