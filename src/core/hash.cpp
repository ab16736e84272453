#include "overtake/core/hash.hpp"

#include <cstdio>

namespace overtake::core {

std::string hex64(std::uint64_t value) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(value));
  return buf;
}

}  // namespace overtake::core
