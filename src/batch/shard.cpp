#include "overtake/batch/shard.hpp"

#include <stdexcept>

#include "overtake/base/errors.hpp"

namespace overtake::batch {

Shard parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  try {
    if (slash == std::string::npos) throw std::invalid_argument("no slash");
    std::size_t used_i = 0;
    std::size_t used_n = 0;
    const int i = std::stoi(text.substr(0, slash), &used_i);
    const int n = std::stoi(text.substr(slash + 1), &used_n);
    if (used_i != slash || used_n != text.size() - slash - 1) throw std::invalid_argument("junk");
    if (n < 1 || i < 1 || i > n) {
      throw base::UsageError("--shard: '" + text + "' is out of range (I/N needs 1 <= I <= N)");
    }
    return {i, n};
  } catch (const std::logic_error&) {
    throw base::UsageError("--shard: '" + text + "' is not of the form I/N (e.g. 2/8)");
  }
}

void check_shard(const Shard& shard) {
  if (shard.count < 1 || shard.index < 1 || shard.index > shard.count) {
    throw base::UsageError("--shard: " + shard.text() + " is out of range");
  }
}

}  // namespace overtake::batch
