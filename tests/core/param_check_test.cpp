// The parameter checker: each check names the key (with the prefix) and the value, and passes
// silently on a good value.

#include "overtake/core/param_check.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace overtake::core {
namespace {

TEST(ParamChecker, GoodValuesAddNothing) {
  std::vector<std::string> out;
  ParamChecker c(out, "world.");
  c.positive("a", 1.0);
  c.non_negative("b", 0.0);
  c.non_negative("n", 0);
  c.finite("c", -3.0);
  c.in_range("d", 0.5, 0.0, 1.0);
  c.in_range("e", 3, 1, 8);
  c.at_most("f", 2.0, 2.0, "g");
  c.at_least("h", 1, 1);
  c.ordered("lo", 1.0, "hi", 1.0);
  c.positive_list("l", {1.0, 2.0});
  c.require(true, "r", "must hold", 1.0);
  c.require(true, "r", "must hold");
  EXPECT_TRUE(out.empty());
}

TEST(ParamChecker, EachCheckNamesTheKeyAndTheValue) {
  std::vector<std::string> out;
  ParamChecker c(out, "world.");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  c.positive("a", 0.0);
  c.non_negative("b", -0.5);
  c.non_negative("n", -2);
  c.finite("c", std::numeric_limits<double>::infinity());
  c.in_range("d", nan, 0.0, 1.0);
  c.in_range("e", 1000000, 1, 8);
  c.at_most("f", 3.0, 2.0, "g");
  c.at_least("h", 0, 1);
  c.ordered("lo", 3.0, "hi", 2.0);
  c.positive_list("l", {});
  c.positive_list("m", {1.0, -1.0});
  c.require(false, "r", "must hold", 1e308);
  c.require(false, "s", "must hold");
  const std::vector<std::string> want = {
      "world.a must be a positive number (got 0)",
      "world.b must be zero or more (got -0.5)",
      "world.n must be zero or more (got -2)",
      "world.c must be finite",
      "world.d must be between 0 and 1 (got nan)",
      "world.e must be between 1 and 8 (got 1000000)",
      "world.f must be at most g (got 3)",
      "world.h must be at least 1 (got 0)",
      "world.lo (3) must not exceed world.hi (2)",
      "world.l must list at least one value",
      "world.m must hold positive numbers (got -1)",
      "world.r must hold (got 1e+308)",
      "world.s must hold",
  };
  EXPECT_EQ(out, want);
}

TEST(ParamChecker, TwoCheckersWithOtherPrefixesShareOneList) {
  std::vector<std::string> out;
  ParamChecker(out, "planner.").positive("x", -1.0);
  ParamChecker(out).positive("world.step_s", 0.0);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0], "planner.x must be a positive number (got -1)");
  EXPECT_EQ(out[1], "world.step_s must be a positive number (got 0)");
}

}  // namespace
}  // namespace overtake::core
