// Map files on disk (the app reads them; the core parses text): a file gives the same map as
// its text, and a file that cannot be read is an error naming it.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "overtake/run/map_file.hpp"
#include "overtake/run/resources.hpp"

namespace overtake::run {

namespace {

using ::testing::HasSubstr;

TEST(MapFile, LoadsFromDiskWithTheSameResultAsText) {
  const auto text = resources::embedded_file("tracks/default.csv");
  ASSERT_TRUE(text);
  const auto path = std::filesystem::temp_directory_path() / "overtake_map_file_test.csv";
  {
    std::ofstream out(path, std::ios::binary);
    out << *text;
  }
  const core::Map a = load_map_file(path);
  const core::Map b = core::parse_map(*text, path.string());
  EXPECT_EQ(a.waypoints, b.waypoints);
  EXPECT_EQ(a.content_hash, b.content_hash);
  EXPECT_EQ(a.source, path.string());
  std::filesystem::remove(path);
}

TEST(MapFile, AMissingFileNamesThePath) {
  try {
    (void)load_map_file("/nonexistent/dir/map.csv");
    FAIL() << "expected MapError";
  } catch (const core::MapError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("/nonexistent/dir/map.csv: cannot open"));
  }
}

TEST(MapFile, AFaultNamesTheFile) {
  const auto path = std::filesystem::temp_directory_path() / "overtake_map_file_bad.csv";
  {
    std::ofstream out(path, std::ios::binary);
    out << "1 2 3\n";
  }
  try {
    (void)load_map_file(path);
    FAIL() << "expected MapError";
  } catch (const core::MapError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr(path.string()));
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace overtake::run
