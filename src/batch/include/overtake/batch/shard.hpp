#pragma once
// The one shard rule of the batch room: shard I of N holds the items k of a list with
// k mod N == I - 1 (a bench's runs, a hunt's, a Slurm array's tasks). Round robin, so that
// every shard gets a share of each policy, traffic and seed, and shard sizes differ by one.

#include <cstddef>
#include <string>

namespace overtake::batch {

/// Shard `index` of `count` (1 <= index <= count); 1/1 is the whole list.
struct Shard {
  int index = 1;  ///< 1-based
  int count = 1;

  /// Whether item `item` of the list (from 0) is this shard's.
  [[nodiscard]] bool holds(std::size_t item) const {
    return item % static_cast<std::size_t>(count) == static_cast<std::size_t>(index - 1);
  }
  /// How many items of a list of `total` are this shard's.
  [[nodiscard]] std::size_t size_of(std::size_t total) const {
    const auto n = static_cast<std::size_t>(count);
    const auto i = static_cast<std::size_t>(index - 1);
    return total / n + (i < total % n ? 1 : 0);
  }
  /// The list's index of this shard's `j`-th item (from 0).
  [[nodiscard]] std::size_t item(std::size_t j) const {
    return static_cast<std::size_t>(index - 1) + static_cast<std::size_t>(count) * j;
  }
  /// "I/N".
  [[nodiscard]] std::string text() const {
    return std::to_string(index) + "/" + std::to_string(count);
  }
  friend bool operator==(const Shard&, const Shard&) = default;
};

/// Parses "I/N" (1 <= I <= N). Throws UsageError naming --shard.
[[nodiscard]] Shard parse_shard(const std::string& text);

/// Throws UsageError naming --shard when the shard is out of range (index not in 1..count).
void check_shard(const Shard& shard);

}  // namespace overtake::batch
