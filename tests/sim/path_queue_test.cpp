// The original's rule for taking a new path (simulator.md, "Time and the ego car").

#include <gtest/gtest.h>

#include <vector>

#include "overtake/sim/path_queue.hpp"

namespace overtake::sim {
namespace {

using core::Vec2;

const std::vector<Vec2> kPath{{0, 0}, {1, 0}, {2, 0}, {3, 0}, {4, 0}};

TEST(PathTrim, NearestIsNotFirstDropsItAndEverythingBefore) {
  const auto q = trim_new_path(kPath, {2.1, 0.2}, 1e-3);
  ASSERT_EQ(q.size(), 2u);
  EXPECT_EQ(q.front(), (Vec2{3, 0}));
}

TEST(PathTrim, NearestIsFirstAndCarNotOnItKeepsIt) {
  const auto q = trim_new_path(kPath, {-0.4, 0.0}, 1e-3);
  ASSERT_EQ(q.size(), 5u);
  EXPECT_EQ(q.front(), (Vec2{0, 0}));
}

TEST(PathTrim, NearestIsFirstAndCarStandsOnItDropsIt) {
  const auto q = trim_new_path(kPath, {0.0, 0.0}, 1e-3);
  ASSERT_EQ(q.size(), 4u);
  EXPECT_EQ(q.front(), (Vec2{1, 0}));
  // Within the tolerance counts as standing on it.
  EXPECT_EQ(trim_new_path(kPath, {0.0005, 0.0}, 1e-3).size(), 4u);
}

TEST(PathTrim, NearestIsLastLeavesNothing) {
  EXPECT_TRUE(trim_new_path(kPath, {10.0, 0.0}, 1e-3).empty());
}

TEST(PathTrim, EmptyPathLeavesNothing) {
  EXPECT_TRUE(trim_new_path({}, {0.0, 0.0}, 1e-3).empty());
}

TEST(PathTrim, TiesGoToTheEarliestPoint) {
  const std::vector<Vec2> path{{0, 0}, {2, 0}, {4, 0}};
  // Equidistant from points 0 and 1: point 0 is nearest (the first), car not on it: kept.
  EXPECT_EQ(trim_new_path(path, {1.0, 0.0}, 1e-3).size(), 3u);
}

}  // namespace
}  // namespace overtake::sim
