#include "overtake/app/bench.hpp"
#include "overtake/app/build_info.hpp"
#include "overtake/app/cli.hpp"

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

#include "overtake/app/commands.hpp"
#include "overtake/app/config.hpp"
#include "overtake/app/io.hpp"
#include "overtake/app/program_planner.hpp"
#include "overtake/app/viewer.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/core/text_check.hpp"
#include "overtake/core/units.hpp"
#include "overtake/eval/summary.hpp"
#include "overtake/sim/referee.hpp"

namespace overtake::app {
namespace {

using nlohmann::json;

constexpr int kMaxJobs = 256;
constexpr int kMaxRecordWorst = 1000;
constexpr const char* kRunsFile = kBenchRunsFile;
constexpr const char* kManifestFile = kBenchManifestFile;
constexpr const char* kLogsDir = "logs";  ///< planner programs' output, one file per run

// Where a planner program's output goes for one run (other planners write none).
std::filesystem::path planner_log_path(const std::filesystem::path& dir, const std::string& policy,
                                       const std::string& traffic, std::uint64_t seed) {
  return dir / (policy + "-" + traffic + "-seed" + std::to_string(seed) + ".log");
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
            {"shard", std::to_string(spec.shard_index) + "/" + std::to_string(spec.shard_count)},
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
  write_file_atomic(out / "summary.csv", eval::summary_csv(s.rows));
  write_file_atomic(out / "pairs.csv", eval::pairs_csv(s.pairs));
  const json summary{{"rows", s.rows},
                     {"pairs", s.pairs},
                     {"verdicts", eval::verdict_method(eval::family_size(s.pairs))}};
  write_file_atomic(out / "summary.json", json_text(summary, 2) + "\n");
  outcome.summary_markdown = eval::summary_markdown(s.rows, s.pairs) + map_hints_markdown(runs);
  write_file_atomic(out / "summary.md", outcome.summary_markdown);
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

// Runs the `count` runs with most incidents again with a replay recorded, on `jobs` threads.
std::vector<std::filesystem::path> record_worst(const BenchSpec& spec, std::vector<json> runs,
                                                const Track& track, const Config& config,
                                                const std::atomic<bool>* stop) {
  std::stable_sort(runs.begin(), runs.end(), [](const json& a, const json& b) {
    const double ia = incident_total(a), ib = incident_total(b);
    if (ia != ib) return ia > ib;
    const auto sa = a["config"]["seed"].get<std::uint64_t>(),
               sb = b["config"]["seed"].get<std::uint64_t>();
    if (sa != sb) return sa < sb;
    return a["index"].get<std::size_t>() < b["index"].get<std::size_t>();
  });
  runs.resize(std::min(runs.size(), static_cast<std::size_t>(spec.record_worst)));
  const std::filesystem::path dir = spec.out / kReplaysFolder;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    throw std::runtime_error(dir.string() + ": cannot create the replays folder (" + ec.message() +
                             ")");

  std::vector<std::filesystem::path> written(runs.size());
  std::vector<std::string> errors(runs.size());
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t i = next.fetch_add(1); i < runs.size(); i = next.fetch_add(1)) {
      if (stop && stop->load()) return;
      const json& run = runs[i];
      DriveOptions o;
      o.minutes = spec.minutes;
      o.seed = run["config"]["seed"].get<std::uint64_t>();
      o.traffic = run["config"]["traffic"].get<std::string>();
      o.policy = run["config"]["policy"].get<std::string>();
      o.steps_per_call = spec.steps_per_call;
      o.planners = spec.planners;
      o.planner_log = planner_log_path(spec.out / "replays", o.policy, o.traffic, o.seed);
      const std::filesystem::path file = dir / bench_replay_name(o.policy, o.traffic, o.seed);
      o.record = file;
      try {
        const DriveResult r = drive_on(track, config, o, {}, stop);
        if (r.report.outcome.end == sim::RunEnd::stopped) {  // interrupted: not the bench's run
          std::filesystem::remove(file, ec);
          continue;
        }
        if (stable_report(report_to_json(r.report, r.provenance)) != stable_report(run)) {
          std::fprintf(stderr,
                       "bench: warning: the recorded re-run of %s differs from its bench run\n",
                       file.c_str());
        }
        written[i] = file;
      } catch (const std::exception& e) {
        errors[i] = file.string() + ": " + e.what();
      }
    }
  };
  const int threads = std::max(1, std::min<int>(spec.jobs, static_cast<int>(runs.size())));
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (auto& th : pool) th.join();
  for (const std::string& e : errors) {
    if (!e.empty()) throw std::runtime_error("--record-worst: " + e);
  }
  std::vector<std::filesystem::path> out;
  for (auto& f : written) {
    if (!f.empty()) out.push_back(std::move(f));
  }
  return out;
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
constexpr std::array<const char*, 4> kBenchSummaryFiles = {"summary.md", "summary.csv",
                                                           "summary.json", "pairs.csv"};
constexpr std::array<std::string_view, 2> kBenchFolders = {kReplaysFolder, kLogsDir};

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
  if (spec.jobs < 1 || spec.jobs > kMaxJobs) {
    throw UsageError("--jobs must be between 1 and " + std::to_string(kMaxJobs) + " (got " +
                     std::to_string(spec.jobs) + ")");
  }
  if (spec.shard_count < 1 || spec.shard_index < 1 || spec.shard_index > spec.shard_count) {
    throw UsageError("--shard: " + std::to_string(spec.shard_index) + "/" +
                     std::to_string(spec.shard_count) + " is out of range");
  }
  if (spec.record_worst < 0 || spec.record_worst > kMaxRecordWorst) {
    throw UsageError("--record-worst must be between 0 and " + std::to_string(kMaxRecordWorst) +
                     " (got " + std::to_string(spec.record_worst) + ")");
  }
  for (const auto& p : spec.policies) {
    DriveOptions o;
    o.policy = p;
    o.planners = spec.planners;
    o.minutes = spec.minutes;
    o.steps_per_call = spec.steps_per_call;
    validate_drive_options(o);
  }
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

BenchOutcome run_bench(const BenchSpec& spec, const std::atomic<bool>* stop,
                       const std::function<void(const BenchProgress&)>& progress) {
  // Everything is checked before the first run.
  const PreparedBench prepared = prepare_bench(spec);
  const Config& config = prepared.config;
  const auto& track = prepared.track;
  const auto& all = prepared.all;
  const json& manifest = prepared.manifest;

  std::error_code ec;
  std::filesystem::create_directories(spec.out, ec);
  if (ec)
    throw std::runtime_error(spec.out.string() + ": cannot create the output folder (" +
                             ec.message() + ")");
  const auto runs_path = spec.out / kRunsFile;
  const auto manifest_path = spec.out / kManifestFile;
  std::vector<json> kept;
  if (std::filesystem::exists(runs_path) || std::filesystem::exists(manifest_path)) {
    if (!spec.resume) {
      throw UsageError(
          "--out: " + spec.out.string() +
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
    // Every row kept must be one this bench, on this build, would write.
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
    for (BenchRow& r : file.rows) kept.push_back(std::move(r.run));
    write_file_atomic(runs_path, runs_text(kept));
  } else {
    check_bench_out(spec.out, spec.force,
                    "--out: ", "move it away, choose another --out, or give --force to replace it");
  }
  write_file_atomic(manifest_path, json_text(manifest, 2) + "\n");

  std::set<std::size_t> done_indices;
  for (const json& r : kept) done_indices.insert(r["index"].get<std::size_t>());
  std::vector<BenchCombo> todo;
  for (const auto& c : all) {
    const bool mine = static_cast<int>(c.index % static_cast<std::size_t>(spec.shard_count)) ==
                      spec.shard_index - 1;
    if (mine && !done_indices.count(c.index)) todo.push_back(c);
  }
  std::size_t shard_total = 0;
  for (const auto& c : all) {
    if (static_cast<int>(c.index % static_cast<std::size_t>(spec.shard_count)) ==
        spec.shard_index - 1)
      ++shard_total;
  }

  std::ofstream append(runs_path, std::ios::app);
  if (!append) throw std::runtime_error(runs_path.string() + ": cannot write");
  std::mutex mu;
  std::vector<json> fresh;
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::string failure;
  const std::string git(build_revision());
  const std::string host = host_name();
  BenchProgress prog{kept.size(), shard_total, 0.0, 0.0, 0.0};
  const auto wall0 = std::chrono::steady_clock::now();
  std::atomic<bool> local_stop{false};
  auto stopping = [&] { return local_stop.load() || (stop && stop->load()); };

  std::atomic<int> running{0};
  auto worker = [&] {
    struct Done {
      std::atomic<int>& n;
      ~Done() { --n; }
    } done{running};
    while (!stopping()) {
      const std::size_t i = next.fetch_add(1);
      if (i >= todo.size()) return;
      const BenchCombo& c = todo[i];
      DriveOptions o;
      o.minutes = spec.minutes;
      o.seed = c.seed;
      o.traffic = c.traffic;
      o.policy = c.policy;
      o.steps_per_call = spec.steps_per_call;
      o.planners = spec.planners;
      o.planner_log = planner_log_path(spec.out / kLogsDir, c.policy, c.traffic, c.seed);
      const auto t0 = std::chrono::steady_clock::now();
      DriveResult r;
      try {
        r = drive_on(*track, config, o, {}, stop);
      } catch (const std::exception& e) {
        std::lock_guard lock(mu);
        failure = "run " + c.policy + "/" + c.traffic + "/seed " + std::to_string(c.seed) + ": " +
                  e.what();
        failed = true;
        local_stop = true;
        return;
      }
      if (r.report.outcome.end == sim::RunEnd::stopped) return;  // interrupted: not a finished run
      json line = report_to_json(r.report, r.provenance);
      line["index"] = c.index;
      line["provenance"] = {{"git_revision", git}, {"host", host}};
      line["timing"]["wall_s"] =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      line["timing"]["finished_at"] = utc_now();
      std::lock_guard lock(mu);
      append << json_text(line) << "\n";
      append.flush();
      fresh.push_back(std::move(line));
      ++prog.done;
      prog.simulated_m += r.report.distance_m;
      prog.simulated_s += r.report.duration_s;
    }
  };

  const int threads =
      std::min<int>(spec.jobs, static_cast<int>(std::max<std::size_t>(todo.size(), 1)));
  running = threads;
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads));
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  while (running.load() > 0) {
    if (progress) {
      std::lock_guard lock(mu);
      prog.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
      progress(prog);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  for (auto& th : pool) th.join();
  append.close();
  if (failed) throw std::runtime_error(failure);

  BenchOutcome outcome;
  outcome.runs_new = fresh.size();
  outcome.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  outcome.simulated_s = prog.simulated_s;
  std::vector<json> runs = kept;
  runs.insert(runs.end(), std::make_move_iterator(fresh.begin()),
              std::make_move_iterator(fresh.end()));
  if (progress) {
    prog.wall_s = outcome.wall_s;
    progress(prog);
  }
  outcome.interrupted = stop && stop->load() && runs.size() < shard_total;
  write_outputs(spec.out, runs, manifest, outcome);
  if (spec.record_worst > 0 && !outcome.interrupted) {
    outcome.replays = record_worst(spec, runs, *track, config, stop);
    outcome.interrupted = stop && stop->load();
  }
  return outcome;
}

namespace {

// Copies the shards' recorded replays (replays/*.otr) into out/replays/, as an unsharded
// bench would hold them (each run is in one shard only, so the names do not clash). Returns
// the replays now in out/replays/ that came from the shards, in name order.
std::vector<std::filesystem::path> merge_replays(const std::vector<std::filesystem::path>& dirs,
                                                 const std::filesystem::path& out) {
  namespace fs = std::filesystem;
  const fs::path to = out / kReplaysFolder;
  std::set<fs::path> merged;
  std::error_code ec;
  for (const auto& dir : dirs) {
    const fs::path from = dir / kReplaysFolder;
    if (!fs::is_directory(from, ec)) continue;
    std::set<fs::path> otrs;  // in name order: the same copies whatever the listing order
    for (const auto& entry : fs::directory_iterator(from)) {
      if (entry.path().extension() == ".otr" && entry.is_regular_file(ec))
        otrs.insert(entry.path());
    }
    for (const fs::path& otr : otrs) {
      const fs::path dest = to / otr.filename();
      merged.insert(dest);
      if (fs::equivalent(otr, dest, ec)) continue;  // merging into one of the shards
      fs::create_directories(to, ec);
      if (!fs::copy_file(otr, dest, fs::copy_options::overwrite_existing, ec) || ec) {
        throw std::runtime_error(dest.string() + ": cannot copy the replay " + otr.string() +
                                 " here (" + ec.message() + ")");
      }
    }
  }
  return {merged.begin(), merged.end()};
}

}  // namespace

BenchOutcome merge_bench(const std::vector<std::filesystem::path>& dirs,
                         const std::filesystem::path& out) {
  if (dirs.empty()) throw UsageError("merge: name the bench output folders to join");
  std::optional<json> identity;
  json manifest;
  std::vector<json> runs;
  std::map<std::size_t, std::filesystem::path> seen;  // run -> the folder holding it
  std::optional<BenchBuild> build;                    // one build across every shard's rows
  for (const auto& dir : dirs) {
    json m;
    try {
      m = read_json_file(dir / kManifestFile);
    } catch (const std::exception& e) {
      throw UsageError("merge: " + (dir / kManifestFile).string() + " is missing or unreadable (" +
                       e.what() + ")");
    }
    if (!m.is_object()) {
      throw UsageError("merge: " + (dir / kManifestFile).string() +
                       " is not a bench's manifest (not a JSON object)");
    }
    if (!identity) {
      identity = sweep_identity(m);
      manifest = m;
    } else if (sweep_identity(m) != *identity) {
      throw UsageError("merge: " + dir.string() +
                       " comes from a different bench configuration than " + dirs.front().string() +
                       " (policies, traffic, seeds, minutes, map or parameters differ)");
    }
    const std::filesystem::path file = dir / kRunsFile;
    BenchRowsFile rows;
    try {
      rows = read_bench_rows(file, false);
    } catch (const UsageError& e) {
      throw UsageError("merge: " + std::string(e.what()));
    }
    // The same check as --resume's: each row its run, once, on the sweep's map, length,
    // parameters and build.
    check_bench_rows(rows.rows, m, file, build,
                     "merge: ", "; run every shard of a bench with the same binary and flags");
    for (BenchRow& r : rows.rows) {
      const auto idx = r.run["index"].get<std::size_t>();
      if (const auto [it, first] = seen.emplace(idx, dir); !first) {
        throw UsageError("merge: run " + std::to_string(idx) + " appears twice (in " +
                         it->second.string() + " and " + dir.string() + ")");
      }
      runs.push_back(std::move(r.run));
    }
  }
  if (build) manifest["git_revision"] = build->revision;
  const auto total = manifest["combinations"].get<std::size_t>();
  for (const auto& dir : dirs) {
    if (same_file(dir, out)) {
      throw UsageError("merge: --out " + out.string() + " is one of the folders being joined (" +
                       dir.string() + "); its results would be rewritten: merge into a new folder");
    }
  }
  if (std::filesystem::exists(out / kRunsFile) || std::filesystem::exists(out / kManifestFile)) {
    throw UsageError("merge: --out " + out.string() +
                     " already holds bench results; merge into a new folder");
  }
  check_bench_out(out, false, "merge: --out: ", "move it away, or merge into a new folder");
  if (runs.size() != total) {
    throw UsageError("merge: the folders hold " + std::to_string(runs.size()) + " of the sweep's " +
                     std::to_string(total) + " runs; a shard is missing or unfinished");
  }
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec)
    throw std::runtime_error(out.string() + ": cannot create the output folder (" + ec.message() +
                             ")");
  manifest["shard"] = "1/1";
  write_file_atomic(out / kManifestFile, json_text(manifest, 2) + "\n");
  BenchOutcome outcome;
  write_outputs(out, runs, manifest, outcome);
  outcome.replays = merge_replays(dirs, out);
  return outcome;
}

}  // namespace overtake::app
