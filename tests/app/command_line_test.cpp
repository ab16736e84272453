// The command line as people meet it: `overtake` alone lists what it can do, and a mistyped
// command names the one that was meant.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "overtake/app/cli.hpp"
#include "overtake/base/errors.hpp"

namespace overtake::app {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

struct Outcome {
  int rc = 0;
  std::string out;
  std::string err;
};

Outcome run(std::vector<const char*> args) {
  args.insert(args.begin(), "overtake");
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  Outcome o;
  o.rc = run_cli(static_cast<int>(args.size()), args.data());
  o.out = testing::internal::GetCapturedStdout();
  o.err = testing::internal::GetCapturedStderr();
  return o;
}

// The commands a `--help` of each answers to, as CLI11 registered them.
std::vector<std::string> registered_commands() {
  CLI::App app;
  static_cast<void>(register_commands(app));
  std::vector<std::string> names;
  for (const CLI::App* c : app.get_subcommands([](const CLI::App*) { return true; }))
    names.push_back(c->get_name());
  return names;
}

TEST(CommandLine, AloneItListsEveryCommandWithALineEach) {
  const Outcome o = run({});
  EXPECT_EQ(o.rc, base::kExitOk);
  EXPECT_THAT(o.out, HasSubstr("usage: overtake <command>"));
  const std::vector<std::string> names = registered_commands();
  ASSERT_GE(names.size(), 11U);
  for (const std::string& name : names) {
    // "  NAME" padded, then its summary on the same line.
    const auto at = o.out.find("\n  " + name + " ");
    ASSERT_NE(at, std::string::npos) << name << " is not listed:\n" << o.out;
    const auto end = o.out.find('\n', at + 1);
    EXPECT_GT(end - at, name.size() + 20) << name << " has no summary";
  }
}

TEST(CommandLine, AMistypedCommandNamesTheNearestOne) {
  const Outcome swapped = run({"drvie", "--minutes", "1"});
  EXPECT_EQ(swapped.rc, base::kExitUsage);
  EXPECT_THAT(swapped.err, HasSubstr("'drvie' is not a command; did you mean 'drive'?"));
  EXPECT_EQ(swapped.out, "");
  EXPECT_THAT(run({"bnech"}).err, HasSubstr("did you mean 'bench'?"));
  EXPECT_THAT(run({"calibrat"}).err, HasSubstr("did you mean 'calibrate'?"));
  EXPECT_THAT(run({"hnut"}).err, HasSubstr("did you mean 'hunt'?"));
}

TEST(CommandLine, AWordFarFromEveryCommandIsNotGuessed) {
  const Outcome o = run({"xylophone"});
  EXPECT_EQ(o.rc, base::kExitUsage);
  EXPECT_THAT(o.err, HasSubstr("'xylophone' is not a command."));
  EXPECT_THAT(o.err, Not(HasSubstr("did you mean")));
  EXPECT_THAT(o.err, HasSubstr("Run `overtake` alone to list the commands"));
}

TEST(CommandLine, OptionsBeforeACommandStillReachTheParser) {
  const Outcome o = run({"--no-such-flag"});
  EXPECT_EQ(o.rc, base::kExitUsage);
  EXPECT_THAT(o.err, Not(HasSubstr("is not a command")));
}

}  // namespace
}  // namespace overtake::app
