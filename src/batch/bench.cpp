#include "overtake/batch/bench.hpp"
#include "overtake/base/build_info.hpp"

#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "bench_internal.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/bench_page.hpp"
#include "overtake/batch/merge.hpp"
#include "overtake/batch/policies.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/core/text_check.hpp"
#include "overtake/core/units.hpp"
#include "overtake/eval/summary.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/planners/program_planner.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/pages.hpp"
#include "overtake/run/report.hpp"
#include "overtake/sim/referee.hpp"

namespace overtake::batch {

using base::build_revision;
using base::check_unique_names;
using base::json_text;
using base::same_file;
using base::UsageError;
using base::write_file_atomic;
using planners::PlannerEntry;
using planners::PlannerKind;
using planners::program_isolated;
using run::Config;
using run::config_hash;
using run::drive_on;
using run::DriveOptions;
using run::DriveResult;
using run::load_config;
using run::load_track;
using run::read_json_file;
using run::report_to_json;
using run::Track;
using run::validate_drive_options;
namespace {

using nlohmann::json;

constexpr int kMaxRecordWorst = 1000;
constexpr const char* kRunsFile = kBenchRunsFile;
constexpr const char* kManifestFile = kBenchManifestFile;

// Where a planner program's output goes for one run (other planners write none); `what` tells
// apart the re-run with a replay (".recorded"), so that it keeps the bench run's log.
std::filesystem::path planner_log_path(const std::filesystem::path& out, const std::string& policy,
                                       const std::string& traffic, std::uint64_t seed,
                                       const std::string& what = "") {
  return out / kBenchLogsFolder /
         (policy + "-" + traffic + "-seed" + std::to_string(seed) + what + ".log");
}

std::string host_name() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::uint64_t parse_u64(const std::string& s, const std::string& whole) {
  std::uint64_t value = 0;
  const char* end = s.data() + s.size();
  const auto [ptr, ec] = std::from_chars(s.data(), end, value);
  if (s.empty() || ptr != end || (ec != std::errc() && ec != std::errc::result_out_of_range)) {
    throw UsageError("--seeds: '" + whole + "' is not a list of seeds like 1-20 or 1,4,9");
  }
  if (ec == std::errc::result_out_of_range) {
    throw UsageError("--seeds: '" + s + "' is out of range: a seed is a whole number from 0 to " +
                     "18446744073709551615");
  }
  return value;
}

// The manifest: what defines a sweep (everything but the shard).
json manifest_of(const BenchSpec& spec, const Track& track, const Config& config,
                 std::size_t total) {
  json planners = json::object();  // the policies brought by flags: what each one is
  if (spec.planners) {
    for (const auto& p : spec.policies) {
      const PlannerEntry* e = spec.planners->find(p);
      if (e && e->kind != PlannerKind::builtin) planners[p] = json::parse(e->describe());
    }
  }
  json m = {{"policies", spec.policies},
            {"traffic", spec.traffic},
            {"seeds", spec.seeds},
            {"minutes", spec.minutes},
            {"steps_per_call", spec.steps_per_call},
            {"map", {{"path", track.map.source}, {"hash", core::hex64(track.map.content_hash)}}},
            {"params_hash", config_hash(config)},
            {"combinations", total},
            {"shard", spec.shard().text()},
            {"git_revision", std::string(build_revision())}};
  if (!planners.empty()) m["planners"] = planners;
  return m;
}

// What a bench is, whichever build ran it (the build is checked on its own, and named).
json without_revision(json manifest) {
  manifest.erase("git_revision");
  return manifest;
}

// What makes shards one sweep: the bench without its shard (nor its build).
json sweep_identity(json manifest) {
  manifest.erase("shard");
  return without_revision(std::move(manifest));
}

std::string runs_text(std::vector<json> runs) {
  std::sort(runs.begin(), runs.end(), [](const json& a, const json& b) {
    return a["index"].get<std::size_t>() < b["index"].get<std::size_t>();
  });
  std::string out;
  for (const json& r : runs) out += json_text(r) + "\n";
  return out;
}

// Per planner whose runs carry a map hint (report.cpp, map_hint): how many, and the hint.
std::string map_hints_markdown(const std::vector<json>& runs) {
  std::map<std::string, std::pair<std::size_t, std::size_t>> counts;  // policy: hinted, runs
  std::map<std::string, std::string> hint;
  for (const json& r : runs) {
    const auto config = r.find("config");
    if (config == r.end() || !config->is_object()) continue;
    const std::string policy = config->value("policy", "");
    ++counts[policy].second;
    const auto h = r.find("map_hint");
    if (h == r.end() || !h->is_string()) continue;
    ++counts[policy].first;
    if (!hint.count(policy)) hint[policy] = h->get<std::string>();
  }
  std::string text;
  for (const auto& [policy, n] : counts) {
    if (n.first == 0) continue;
    text += "\n**Hint for " + policy + "**: in " + std::to_string(n.first) + " of " +
            std::to_string(n.second) + " runs " + hint[policy] + ".\n";
  }
  return text;
}

void write_outputs(const std::filesystem::path& out, const std::vector<json>& runs,
                   const json& manifest, BenchOutcome& outcome) {
  write_file_atomic(out / kRunsFile, runs_text(runs));
  outcome.summary = summarize_bench(runs, manifest["policies"].get<std::vector<std::string>>(),
                                    manifest["traffic"].get<std::vector<std::string>>(),
                                    (out / kRunsFile).string());
  const BenchSummary& s = outcome.summary;
  write_file_atomic(out / kBenchSummaryCsvFile, eval::summary_csv(s.rows));
  write_file_atomic(out / kBenchPairsFile, eval::pairs_csv(s.pairs));
  const json summary{{"rows", s.rows},
                     {"pairs", s.pairs},
                     {"verdicts", eval::verdict_method(eval::family_size(s.pairs))}};
  write_file_atomic(out / kBenchSummaryJsonFile, json_text(summary, 2) + "\n");
  outcome.summary_markdown = eval::summary_markdown(s.rows, s.pairs) + map_hints_markdown(runs);
  write_file_atomic(out / kBenchSummaryMarkdownFile, outcome.summary_markdown);
  outcome.runs_done = runs.size();
}

double incident_total(const json& run) {
  double n = 0.0;
  for (const auto& [type, count] : run["incident_counts"].items()) n += count.get<double>();
  return n;
}

// A run's report without what measures time or place (for comparing a re-run with it).
json stable_report(json run) {
  for (const char* key : {"timing", "provenance", "index"}) run.erase(key);
  return run;
}

// The `count` runs with most incidents (ties: lower seed first, then run order).
std::vector<json> worst_runs(std::vector<json> runs, int count) {
  std::stable_sort(runs.begin(), runs.end(), [](const json& a, const json& b) {
    const double ia = incident_total(a), ib = incident_total(b);
    if (ia != ib) return ia > ib;
    const auto sa = a["config"]["seed"].get<std::uint64_t>(),
               sb = b["config"]["seed"].get<std::uint64_t>();
    if (sa != sb) return sa < sb;
    return a["index"].get<std::size_t>() < b["index"].get<std::size_t>();
  });
  runs.resize(std::min(runs.size(), static_cast<std::size_t>(count)));
  return runs;
}

// Drives a bench run again with its replay recorded; the replay's path, or empty when it was
// interrupted (then the replay is removed: it is not the bench's run).
std::filesystem::path record_run(const BenchSpec& spec, const json& run, const Track& track,
                                 const Config& config, const std::atomic<bool>* halt) {
  DriveOptions o;
  o.minutes = spec.minutes;
  o.seed = run["config"]["seed"].get<std::uint64_t>();
  o.traffic = run["config"]["traffic"].get<std::string>();
  o.policy = run["config"]["policy"].get<std::string>();
  o.steps_per_call = spec.steps_per_call;
  o.planners = spec.planners;
  o.planner_log = planner_log_path(spec.out, o.policy, o.traffic, o.seed, ".recorded");
  const std::filesystem::path file =
      spec.out / kReplaysFolder / bench_replay_name(o.policy, o.traffic, o.seed);
  o.record = file;
  try {
    const DriveResult r = drive_on(track, config, o, {}, halt);
    if (r.report.outcome.end == sim::RunEnd::stopped) {
      std::error_code ec;
      std::filesystem::remove(file, ec);
      return {};
    }
    if (stable_report(report_to_json(r.report, r.provenance)) != stable_report(run)) {
      std::fprintf(stderr, "bench: warning: the recorded re-run of %s differs from its bench run\n",
                   file.c_str());
    }
  } catch (const std::exception& e) {
    throw std::runtime_error("--record-worst: " + file.string() + ": " + e.what());
  }
  return file;
}

// Runs the `record_worst` runs with most incidents again with a replay recorded, on the
// bench's jobs; the replays written, in the order of the runs chosen.
std::vector<std::filesystem::path> record_worst(const BenchSpec& spec, const std::vector<json>& all,
                                                const Track& track, const Config& config,
                                                const std::atomic<bool>* stop) {
  const std::vector<json> runs = worst_runs(all, spec.record_worst);
  const std::filesystem::path dir = spec.out / kReplaysFolder;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    throw std::runtime_error(dir.string() + ": cannot create the replays folder (" + ec.message() +
                             ")");
  std::vector<std::filesystem::path> written;
  (void)run_pool<std::filesystem::path>(
      runs.size(), {spec.jobs, stop, PoolOrder::by_index, {}},
      [&](std::size_t i, const std::atomic<bool>* halt) {
        return record_run(spec, runs[i], track, config, halt);
      },
      [&](std::size_t /*i*/, std::filesystem::path&& file) {
        if (!file.empty()) written.push_back(std::move(file));
        return true;
      });
  return written;
}

}  // namespace

std::vector<json> load_bench_runs(const std::filesystem::path& dir, std::size_t* dropped) {
  BenchRowsFile file = read_bench_rows(dir / kRunsFile, true);
  if (dropped) *dropped = file.cut_off_line > 0 ? 1 : 0;
  std::vector<json> runs;
  runs.reserve(file.rows.size());
  for (BenchRow& r : file.rows) runs.push_back(std::move(r.run));
  std::stable_sort(runs.begin(), runs.end(), [](const json& a, const json& b) {
    return a["index"].get<std::size_t>() < b["index"].get<std::size_t>();
  });
  return runs;
}

std::vector<std::uint64_t> parse_seed_list(const std::string& text) {
  std::vector<std::uint64_t> seeds;
  std::stringstream ss(text);
  std::string part;
  while (std::getline(ss, part, ',')) {
    const auto dash = part.find('-');
    if (dash == std::string::npos) {
      seeds.push_back(parse_u64(part, text));
      continue;
    }
    const std::uint64_t lo = parse_u64(part.substr(0, dash), text);
    const std::uint64_t hi = parse_u64(part.substr(dash + 1), text);
    if (hi < lo)
      throw UsageError("--seeds: the range '" + part + "' is empty (" + std::to_string(lo) + " > " +
                       std::to_string(hi) + ")");
    if (hi - lo > 1000000) throw UsageError("--seeds: the range '" + part + "' is too large");
    for (std::uint64_t s = lo; s <= hi; ++s) seeds.push_back(s);
  }
  if (seeds.empty()) throw UsageError("--seeds: no seeds given (e.g. --seeds 1-20)");
  std::set<std::uint64_t> unique(seeds.begin(), seeds.end());
  if (unique.size() != seeds.size()) throw UsageError("--seeds: '" + text + "' names a seed twice");
  return seeds;
}

namespace {

// The files and folders a bench writes besides runs.jsonl and bench.json.
constexpr std::array<const char*, 4> kBenchSummaryFiles = {
    kBenchSummaryMarkdownFile, kBenchSummaryCsvFile, kBenchSummaryJsonFile, kBenchPairsFile};
constexpr std::array<std::string_view, 2> kBenchFolders = {kReplaysFolder, kBenchLogsFolder};

}  // namespace

void check_bench_out(const std::filesystem::path& out, bool force, const std::string& who,
                     const std::string& remedy) {
  if (force) return;
  std::error_code ec;
  const auto refuse = [&](const std::filesystem::path& what) {
    throw UsageError(who + what.string() +
                     " is not a bench's (the folder holds no bench.json): a bench would replace "
                     "it; " +
                     remedy);
  };
  for (const char* name : kBenchSummaryFiles) {
    if (std::filesystem::exists(std::filesystem::symlink_status(out / name, ec)))
      refuse(out / name);
  }
  for (const std::string_view name : kBenchFolders) {
    const std::filesystem::path dir = out / name;
    if (!std::filesystem::exists(std::filesystem::symlink_status(dir, ec))) continue;
    if (!std::filesystem::is_directory(dir, ec) || !std::filesystem::is_empty(dir, ec)) refuse(dir);
  }
}

namespace {

// What a bench needs before its first run, every input checked.
struct PreparedBench {
  Config config;
  std::shared_ptr<const Track> track;
  std::vector<BenchCombo> all;
  json manifest;
};

PreparedBench prepare_bench(const BenchSpec& spec) {
  if (spec.policies.empty()) throw UsageError("--policies: no policy given");
  if (spec.traffic.empty()) throw UsageError("--traffic: no traffic profile given");
  if (spec.seeds.empty()) throw UsageError("--seeds: no seeds given");
  check_unique_names(spec.policies, "--policies");
  check_unique_names(spec.traffic, "--traffic");
  if (std::set<std::uint64_t>(spec.seeds.begin(), spec.seeds.end()).size() != spec.seeds.size())
    throw UsageError("--seeds: a seed is named twice");
  check_jobs(spec.jobs);
  check_shard(spec.shard());
  if (spec.record_worst < 0 || spec.record_worst > kMaxRecordWorst) {
    throw UsageError("--record-worst must be between 0 and " + std::to_string(kMaxRecordWorst) +
                     " (got " + std::to_string(spec.record_worst) + ")");
  }
  DriveOptions run;  // what every run shares: its length and steps per call
  run.policy = spec.policies.front();
  run.planners = spec.planners;
  run.minutes = spec.minutes;
  run.steps_per_call = spec.steps_per_call;
  validate_drive_options(run);
  check_policy_names(spec.policies, spec.planners);
  for (const auto& t : spec.traffic) {
    DriveOptions o;
    o.traffic = t;
    validate_drive_options(o);
  }
  for (const auto& p : spec.policies) {  // isolated networks that cannot be had: now
    const PlannerEntry* e = spec.planners ? spec.planners->find(p) : nullptr;
    if (e && e->program) (void)program_isolated(*e);
  }
  PreparedBench p;
  p.config = load_config(spec.config);
  p.track = load_track(spec.map);
  p.all = bench_combinations(spec);
  p.manifest = manifest_of(spec, *p.track, p.config, p.all.size());
  return p;
}

}  // namespace

void check_bench_spec(const BenchSpec& spec) {
  (void)prepare_bench(spec);
}

namespace {

// The rows of a bench being resumed in spec.out, each checked to be one this bench, on this
// build, would write (runs.jsonl is rewritten with them, without a line cut off by a kill).
std::vector<json> resumed_rows(const BenchSpec& spec, const json& manifest) {
  const auto runs_path = spec.out / kRunsFile;
  const auto manifest_path = spec.out / kManifestFile;
  if (!spec.resume) {
    throw UsageError("--out: " + spec.out.string() +
                     " already holds bench results; use --resume to continue it, or another --out");
  }
  json old;
  try {
    old = read_json_file(manifest_path);
  } catch (const std::exception& e) {
    throw UsageError("--resume: " + manifest_path.string() + " is missing or unreadable (" +
                     e.what() + ")");
  }
  if (!old.is_object() || without_revision(old) != without_revision(manifest)) {
    throw UsageError("--resume: " + spec.out.string() +
                     " holds a different bench (policies, traffic, seeds, minutes, map, "
                     "parameters or shard differ)");
  }
  const std::string hint =
      "; the folder cannot be resumed (move it away, or bench into another --out)";
  BenchRowsFile file;
  try {
    file = read_bench_rows(runs_path, true);
  } catch (const UsageError& e) {
    throw UsageError("--resume: " + std::string(e.what()) + hint);
  }
  if (file.cut_off_line > 0) {
    std::fprintf(stderr,
                 "bench: %s:%zu was cut off (a run written when the bench was killed); its run "
                 "is driven again\n",
                 runs_path.c_str(), file.cut_off_line);
  }
  std::optional<BenchBuild> build = BenchBuild{std::string(build_revision()), "this overtake"};
  check_bench_rows(file.rows, old, runs_path, build, "--resume: ", hint);
  std::vector<json> kept;
  for (BenchRow& r : file.rows) kept.push_back(std::move(r.run));
  write_file_atomic(runs_path, runs_text(kept));
  return kept;
}

// Makes spec.out ready for the bench (its folder, the rows kept when resuming, its manifest);
// the rows kept.
std::vector<json> open_bench_out(const BenchSpec& spec, const json& manifest) {
  std::error_code ec;
  std::filesystem::create_directories(spec.out, ec);
  if (ec)
    throw std::runtime_error(spec.out.string() + ": cannot create the output folder (" +
                             ec.message() + ")");
  std::vector<json> kept;
  if (std::filesystem::exists(spec.out / kRunsFile) ||
      std::filesystem::exists(spec.out / kManifestFile)) {
    kept = resumed_rows(spec, manifest);
  } else {
    check_bench_out(spec.out, spec.force,
                    "--out: ", "move it away, choose another --out, or give --force to replace it");
  }
  write_file_atomic(spec.out / kManifestFile, json_text(manifest, 2) + "\n");
  return kept;
}

// The runs of the spec's shard not yet among `kept`.
std::vector<BenchCombo> runs_to_do(const BenchSpec& spec, const std::vector<BenchCombo>& all,
                                   const std::vector<json>& kept) {
  std::set<std::size_t> done;
  for (const json& r : kept) done.insert(r["index"].get<std::size_t>());
  std::vector<BenchCombo> todo;
  for (const BenchCombo& c : all) {
    if (spec.shard().holds(c.index) && !done.count(c.index)) todo.push_back(c);
  }
  return todo;
}

// A run driven: its row of runs.jsonl, and what the progress line counts.
struct FinishedRun {
  json line;
  double distance_m = 0.0;
  double duration_s = 0.0;
};

// One run of the sweep driven; nullopt when it was interrupted.
std::optional<FinishedRun> drive_bench_run(const BenchSpec& spec, const PreparedBench& prepared,
                                           const BenchCombo& c, const std::string& host,
                                           const std::atomic<bool>* halt) {
  DriveOptions o;
  o.minutes = spec.minutes;
  o.seed = c.seed;
  o.traffic = c.traffic;
  o.policy = c.policy;
  o.steps_per_call = spec.steps_per_call;
  o.planners = spec.planners;
  o.planner_log = planner_log_path(spec.out, c.policy, c.traffic, c.seed);
  const auto t0 = std::chrono::steady_clock::now();
  DriveResult r;
  try {
    r = drive_on(*prepared.track, prepared.config, o, {}, halt);
  } catch (const std::exception& e) {
    throw std::runtime_error("run " + c.policy + "/" + c.traffic + "/seed " +
                             std::to_string(c.seed) + ": " + e.what());
  }
  if (r.report.outcome.end == sim::RunEnd::stopped) return std::nullopt;
  json line = report_to_json(r.report, r.provenance);
  line["index"] = c.index;
  line["provenance"] = {{"git_revision", std::string(build_revision())}, {"host", host}};
  line["timing"]["wall_s"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  line["timing"]["finished_at"] = utc_now();
  return FinishedRun{std::move(line), r.report.distance_m, r.report.duration_s};
}

// Drives `todo` on the spec's jobs, appending each finished run to runs.jsonl as it comes (an
// interrupted bench keeps every finished run); the runs made, in the order they finished.
std::vector<json> drive_bench_runs(const BenchSpec& spec, const PreparedBench& prepared,
                                   const std::vector<BenchCombo>& todo, BenchProgress& prog,
                                   const std::atomic<bool>* stop,
                                   const std::function<void(const BenchProgress&)>& progress) {
  const auto runs_path = spec.out / kRunsFile;
  std::ofstream append(runs_path, std::ios::app);
  if (!append) throw std::runtime_error(runs_path.string() + ": cannot write");
  const std::string host = host_name();
  const auto wall0 = std::chrono::steady_clock::now();
  std::vector<json> fresh;
  PoolOptions pool{spec.jobs, stop, PoolOrder::as_finished, {}};
  pool.tick = [&] {
    prog.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    if (progress) progress(prog);
  };
  (void)run_pool<std::optional<FinishedRun>>(
      todo.size(), pool,
      [&](std::size_t i, const std::atomic<bool>* halt) {
        return drive_bench_run(spec, prepared, todo[i], host, halt);
      },
      [&](std::size_t /*i*/, std::optional<FinishedRun>&& run) {
        if (!run) return true;
        append << json_text(run->line) << "\n";
        append.flush();
        ++prog.done;
        prog.simulated_m += run->distance_m;
        prog.simulated_s += run->duration_s;
        fresh.push_back(std::move(run->line));
        return true;
      });
  prog.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return fresh;
}

}  // namespace

BenchOutcome run_bench(const BenchSpec& spec, const std::atomic<bool>* stop,
                       const std::function<void(const BenchProgress&)>& progress) {
  // Everything is checked before the first run.
  const PreparedBench prepared = prepare_bench(spec);
  std::vector<json> runs = open_bench_out(spec, prepared.manifest);
  const std::vector<BenchCombo> todo = runs_to_do(spec, prepared.all, runs);
  const std::size_t shard_total = spec.shard().size_of(prepared.all.size());
  BenchProgress prog{runs.size(), shard_total, 0.0, 0.0, 0.0};
  std::vector<json> fresh = drive_bench_runs(spec, prepared, todo, prog, stop, progress);

  BenchOutcome outcome;
  outcome.runs_new = fresh.size();
  outcome.wall_s = prog.wall_s;
  outcome.simulated_s = prog.simulated_s;
  runs.insert(runs.end(), std::make_move_iterator(fresh.begin()),
              std::make_move_iterator(fresh.end()));
  if (progress) progress(prog);
  outcome.interrupted = stop && stop->load() && runs.size() < shard_total;
  write_outputs(spec.out, runs, prepared.manifest, outcome);
  if (spec.record_worst > 0 && !outcome.interrupted) {
    outcome.replays = record_worst(spec, runs, *prepared.track, prepared.config, stop);
    outcome.interrupted = stop && stop->load();
  }
  return outcome;
}

namespace bench_detail {

json sweep_identity(json manifest) {
  return batch::sweep_identity(std::move(manifest));
}

void write_outputs(const std::filesystem::path& out, const std::vector<json>& runs,
                   const json& manifest, BenchOutcome& outcome) {
  batch::write_outputs(out, runs, manifest, outcome);
}

}  // namespace bench_detail

}  // namespace overtake::batch
