#pragma once
// Content hashes for provenance (map files, parameter sets).

#include <cstdint>
#include <string>
#include <string_view>

namespace overtake::core {

/// 64-bit FNV-1a of the bytes.
[[nodiscard]] constexpr std::uint64_t fnv1a64(std::string_view bytes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

/// The hash as 16 lowercase hex digits.
[[nodiscard]] std::string hex64(std::uint64_t value);

}  // namespace overtake::core
