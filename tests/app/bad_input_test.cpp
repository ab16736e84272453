// Input made to break the readers: JSON nested 100,000 deep, files that are not regular files
// (/dev/zero, a FIFO, a directory), names and reasons that are not UTF-8, a path to 1e300 m.
// Each is refused with an error that names it, or written as valid JSON; nothing crashes,
// hangs or reads without bound.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/app/cli.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/core/text_check.hpp"
#include "overtake/run/resources.hpp"
#include "temp_dir.hpp"

namespace overtake::app {

using base::kExitFailure;
using base::kExitOk;
using base::kExitUsage;
using base::read_file;
namespace {

using nlohmann::json;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
namespace fs = std::filesystem;

struct Outcome {
  int rc = 0;
  std::string out;
  std::string err;
};

Outcome cli(std::vector<std::string> args) {
  args.insert(args.begin(), "overtake");
  std::vector<const char*> argv;
  for (const std::string& a : args) argv.push_back(a.c_str());
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  Outcome o;
  o.rc = run_cli(static_cast<int>(argv.size()), argv.data());
  o.out = testing::internal::GetCapturedStdout();
  o.err = testing::internal::GetCapturedStderr();
  return o;
}

void write(const fs::path& p, std::string_view text) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out << text;
}

std::string deep(const std::string& key) {
  return "{\"" + key + "\": " + std::string(100'000, '[') + std::string(100'000, ']') + "}";
}

TEST(BadInput, DeepJsonInAScenarioOrAConfigIsAnErrorNamingTheFile) {
  const test::TempDir dir("overtake-bad-input");
  const fs::path scenario = dir.path() / "deep-scenario.json";
  write(scenario, deep("duration_s"));
  const Outcome s = cli({"drive", "--scenario", scenario.string(), "--quiet"});
  EXPECT_EQ(s.rc, kExitFailure) << s.err;
  EXPECT_THAT(s.err, AllOf(HasSubstr("deep-scenario.json"),
                           HasSubstr("JSON nested deeper than 64 levels (at byte 78)")));
  const fs::path config = dir.path() / "deep-config.json";
  write(config, deep("world"));
  const Outcome c = cli({"drive", "--config", config.string(), "--minutes", "0.01", "--quiet"});
  EXPECT_EQ(c.rc, kExitFailure) << c.err;
  EXPECT_THAT(c.err, AllOf(HasSubstr("deep-config.json"), HasSubstr("nested deeper than 64")));
  // 64 levels are still read (and then judged as any value is).
  write(config, "{\"world\": " + std::string(63, '[') + std::string(63, ']') + "}");
  const Outcome ok = cli({"drive", "--config", config.string(), "--minutes", "0.01", "--quiet"});
  EXPECT_THAT(ok.err, Not(HasSubstr("nested deeper")));
}

TEST(BadInput, DeepJsonInABenchIsAnErrorNamingTheFileAndLine) {
  const test::TempDir dir("overtake-bad-input");
  const fs::path a = dir.path() / "a";
  const Outcome bench = cli({"bench", "--policies", "walkthrough", "--seeds", "1-2", "--minutes",
                             "0.05", "--traffic", "calm", "--quiet", "--out", a.string()});
  ASSERT_EQ(bench.rc, kExitOk) << bench.err;
  const fs::path b = dir.path() / "b";
  fs::copy(a, b, fs::copy_options::recursive);
  {
    std::ofstream runs(b / "runs.jsonl", std::ios::app);
    runs << deep("index") << "\n";
  }
  const Outcome rows = cli({"compare", a.string(), b.string()});
  EXPECT_EQ(rows.rc, kExitFailure) << rows.err;
  EXPECT_THAT(rows.err, AllOf(HasSubstr("runs.jsonl:3"), HasSubstr("nested deeper than 64")));
  // A runs.jsonl that is a FIFO would wait for a writer; /dev/zero would be one endless line.
  fs::remove(b / "runs.jsonl");
  ASSERT_EQ(::mkfifo((b / "runs.jsonl").c_str(), 0600), 0);
  const Outcome fifo = cli({"compare", a.string(), b.string()});
  EXPECT_EQ(fifo.rc, kExitFailure) << fifo.err;
  EXPECT_THAT(fifo.err, HasSubstr("runs.jsonl: is a FIFO, not a regular file"));
  // A seed beyond every integer is read as a double: it was converted to one regardless
  // (undefined behaviour, found by the bench_folder fuzz harness).
  fs::remove(b / "runs.jsonl");
  fs::copy_file(a / "runs.jsonl", b / "runs.jsonl");
  json with_seeds = json::parse(read_file(a / "bench.json"));
  with_seeds["seeds"] = json::parse("[1, 27777777777777777777777777777777777777777777777777]");
  write(b / "bench.json", with_seeds.dump());
  const Outcome seed = cli({"compare", a.string(), b.string()});
  EXPECT_EQ(seed.rc, kExitFailure) << seed.err;
  EXPECT_THAT(seed.err, AllOf(HasSubstr("bench.json is not a bench's manifest"),
                              HasSubstr("a seed is 2.7777777777777777e+49, not a whole number")));
  write(b / "bench.json", deep("minutes"));
  const Outcome manifest = cli({"compare", a.string(), b.string()});
  EXPECT_EQ(manifest.rc, kExitFailure) << manifest.err;
  EXPECT_THAT(manifest.err,
              AllOf(HasSubstr((b / "bench.json").string()), HasSubstr("nested deeper than 64")));
}

TEST(BadInput, ABenchOfMoreThanAMillionRunsIsRefusedBeforeItStarts) {
  const test::TempDir dir("overtake-bad-input");
  const Outcome o = cli({"bench", "--seeds", "1-1000000", "--traffic", "faithful,calm", "--minutes",
                         "0.01", "--quiet", "--out", (dir.path() / "b").string()});
  EXPECT_EQ(o.rc, kExitUsage) << o.err;
  EXPECT_THAT(o.err, HasSubstr("make more than 1000000 runs"));
  EXPECT_FALSE(fs::exists(dir.path() / "b" / "runs.jsonl"));
}

TEST(BadInput, AMapThatIsNotARegularFileIsRefusedAtOnce) {
  const test::TempDir dir("overtake-bad-input");
  const fs::path fifo = dir.path() / "map.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"/dev/zero", "/dev/zero: is a character device, not a regular file"},
      {fifo.string(), "map.fifo: is a FIFO, not a regular file"}};
  for (const auto& [path, why] : cases) {
    const Outcome o = cli({"drive", "--map", path, "--minutes", "0.01", "--quiet"});
    EXPECT_EQ(o.rc, kExitFailure) << path;
    EXPECT_THAT(o.err, HasSubstr(why)) << path;
  }
  try {
    (void)read_file(dir.path());
    FAIL() << "read a directory";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("is a directory, not a regular file"));
  }
}

TEST(BadInput, ReadFileStopsAtItsLimit) {
  const test::TempDir dir("overtake-bad-input");
  const fs::path f = dir.path() / "big.txt";
  write(f, std::string(5000, 'x'));
  EXPECT_EQ(read_file(f, 5000).size(), 5000U);
  try {
    (void)read_file(f, 4999);
    FAIL() << "read past its limit";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("big.txt: larger than the 4999 bytes this reads"));
  }
}

TEST(BadInput, AMapNamedInLatin1StillGivesItsReportAsValidJson) {
  const test::TempDir dir("overtake-bad-input");
  const auto text = resources::embedded_file("tracks/default.csv");
  ASSERT_TRUE(text);
  const fs::path map = dir.path() / "caf\xE9.csv";  // "café" in Latin-1: not UTF-8
  write(map, *text);
  const fs::path report = dir.path() / "report.json";
  const Outcome o = cli(
      {"drive", "--map", map.string(), "--minutes", "0.02", "--json", report.string(), "--quiet"});
  ASSERT_EQ(o.rc, kExitOk) << o.err;
  std::ifstream in(report);
  const std::string written((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(core::is_valid_utf8(written));
  const json j = json::parse(written);
  EXPECT_THAT(written, HasSubstr("caf\xEF\xBF\xBD.csv"));
  EXPECT_EQ(j["end"], "completed");
}

}  // namespace
}  // namespace overtake::app
