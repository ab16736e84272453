#pragma once
// A folder of a test's own under the system's temporary folder, removed with everything in it
// when the test ends.

#include <unistd.h>

#include <filesystem>
#include <string>

namespace overtake::test {

class TempDir {
 public:
  explicit TempDir(const std::string& prefix = "overtake-test") {
    path_ = std::filesystem::temp_directory_path() /
            (prefix + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter_++));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  static inline int counter_ = 0;
  std::filesystem::path path_;
};

}  // namespace overtake::test
