#include "overtake/protocol/log.hpp"

#include <cstdio>

namespace overtake::protocol {

LogFn stderr_log(bool verbose) {
  return [verbose](LogLevel level, std::string_view line) {
    if (level == LogLevel::info && !verbose) return;
    std::fprintf(stderr, "%s%.*s\n", level == LogLevel::warning ? "warning: " : "",
                 static_cast<int>(line.size()), line.data());
    std::fflush(stderr);
  };
}

}  // namespace overtake::protocol
