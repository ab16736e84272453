// The revision a build reports (`overtake --version`, bench rows, replays) is the source tree's
// git revision at build time: `git rev-parse --short=12 HEAD`, when the tree is a git checkout.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include <unistd.h>

#include "overtake/base/build_info.hpp"
#include "overtake/base/io.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/run/pages.hpp"
#include "process_support.hpp"

namespace overtake::app {

using base::build_revision;
using base::overtake_version;
using base::project_version;
using base::read_file;
using batch::BenchSpec;
using batch::run_bench;
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using ::testing::MatchesRegex;

constexpr auto kProcessLimit = std::chrono::seconds(60);

// What a shell command printed (its last newline dropped), or nullopt when it failed.
std::optional<std::string> output_of(const std::string& command) {
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return std::nullopt;
  std::string out;
  std::array<char, 256> buf{};
  while (std::fgets(buf.data(), static_cast<int>(buf.size()), pipe) != nullptr) out += buf.data();
  if (::pclose(pipe) != 0) return std::nullopt;
  if (!out.empty() && out.back() == '\n') out.pop_back();
  return out;
}

// `git rev-parse --short=12 HEAD` of the source tree, or nullopt when the tree is not the top
// of a git checkout (an unpacked archive, no git installed).
std::optional<std::string> source_revision() {
  const std::string git = "git -C '" + std::string(OVERTAKE_SOURCE_DIR) + "' ";
  const auto top = output_of(git + "rev-parse --show-toplevel 2>/dev/null");
  if (!top) return std::nullopt;
  std::error_code ec;
  if (!fs::equivalent(*top, OVERTAKE_SOURCE_DIR, ec)) return std::nullopt;
  return output_of(git + "rev-parse --short=12 HEAD 2>/dev/null");
}

class VersionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("overtake_version_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(VersionTest, TheBinaryReportsTheSourceTreesRevision) {
  const std::optional<std::string> revision = source_revision();
  if (!revision) GTEST_SKIP() << OVERTAKE_SOURCE_DIR << " is not a git checkout";
  const pid_t pid = test::start_overtake({"--version"}, dir_ / "out.txt", dir_ / "err.txt");
  ASSERT_EQ(test::exit_status(pid, kProcessLimit), 0) << read_file(dir_ / "err.txt");
  EXPECT_EQ(read_file(dir_ / "out.txt"),
            "overtake " + std::string(project_version()) + "+" + *revision + "\n");
  EXPECT_EQ(build_revision(), *revision);
  EXPECT_EQ(overtake_version(), std::string(project_version()) + "+" + *revision);
}

TEST_F(VersionTest, TheVersionNamesTheProjectVersionAndARevision) {
  EXPECT_THAT(std::string(project_version()), MatchesRegex("[0-9]+\\.[0-9]+\\.[0-9]+"));
  const std::string revision(build_revision());
  EXPECT_TRUE(revision == "unknown" ||
              (revision.size() == 12 &&
               revision.find_first_not_of("0123456789abcdef") == std::string::npos))
      << revision;
}

TEST_F(VersionTest, BenchRowsCarryTheBuildsRevision) {
  BenchSpec spec;
  spec.policies = {"walkthrough"};
  spec.traffic = {"faithful"};
  spec.seeds = {1};
  spec.minutes = 0.1;
  spec.jobs = 1;
  spec.out = dir_ / "bench";
  (void)run_bench(spec, nullptr, {});
  std::ifstream in(spec.out / "runs.jsonl");
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(json::parse(line)["provenance"]["git_revision"], std::string(build_revision()));
}

}  // namespace
}  // namespace overtake::app
