// A bench folder as `overtake compare` and the Python module's compare() read it: the input's
// first line is its bench.json, the rest its runs.jsonl, written into a folder of the harness's
// own and compared with itself (batch::compare_bench_folders): the manifest read as a JSON file
// (nesting, size), each line read and checked against the manifest (a duplicate, another
// sweep's run, map, length or build), the rows read and the comparison made. A bad folder is
// refused with std::runtime_error (UsageError, ConfigError) naming the file; anything else is a
// finding.

#include <stdlib.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "overtake/batch/bench.hpp"
#include "overtake/eval/compare.hpp"

namespace {

// Memory-backed when the machine has it: the files are written for every input.
std::filesystem::path scratch_root() {
  std::error_code ec;
  if (std::filesystem::is_directory("/dev/shm", ec)) return "/dev/shm";
  return std::filesystem::temp_directory_path();
}

const std::filesystem::path& folder() {
  static const std::filesystem::path dir = [] {
    std::string name = (scratch_root() / "overtake-fuzz-bench.XXXXXX");
    if (::mkdtemp(name.data()) == nullptr) std::abort();
    return std::filesystem::path(name);
  }();
  return dir;
}

void write(const std::filesystem::path& p, std::string_view text) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const std::size_t eol = text.find('\n');
  write(folder() / overtake::batch::kBenchManifestFile, text.substr(0, eol));
  write(folder() / overtake::batch::kBenchRunsFile,
        eol == std::string_view::npos ? std::string_view() : text.substr(eol + 1));
  try {
    overtake::eval::CompareOptions options;
    options.resamples = 200;  // the intervals' code, at a tenth of its cost
    (void)overtake::batch::compare_bench_folders(folder(), folder(), options);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
