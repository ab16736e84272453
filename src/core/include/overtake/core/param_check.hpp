#pragma once
// Checks of parameter values, shared by every module's validate(): each check that fails adds
// one message naming the key and the value, "key must be ... (got value)".

#include <string>
#include <string_view>
#include <vector>

namespace overtake::core {

/// Collects the problems of one module's parameters into `out`, each key prefixed with
/// `prefix` (e.g. "planner.reference."). Numbers must be finite where a check says so; whole
/// numbers are printed as such, others as a stream prints a double.
class ParamChecker {
 public:
  explicit ParamChecker(std::vector<std::string>& out, std::string prefix = {})
      : out_(out), prefix_(std::move(prefix)) {}

  /// More than zero, and finite.
  void positive(std::string_view key, double v);
  /// Zero or more, and finite.
  void non_negative(std::string_view key, double v);
  void non_negative(std::string_view key, int v);
  /// Finite.
  void finite(std::string_view key, double v);
  /// Within [lo, hi] (NaN is not).
  void in_range(std::string_view key, double v, double lo, double hi);
  void in_range(std::string_view key, int v, int lo, int hi);
  /// At most `limit`, the value of the key `limit_key` (named as given, without the prefix).
  void at_most(std::string_view key, double v, double limit, std::string_view limit_key);
  /// At least `lo`.
  void at_least(std::string_view key, int v, int lo);
  /// `lo` (the value of lo_key) not above `hi` (the value of hi_key).
  void ordered(std::string_view lo_key, double lo, std::string_view hi_key, double hi);
  /// A list with at least one value, every one positive and finite.
  void positive_list(std::string_view key, const std::vector<double>& v);
  /// Unless `ok`: "key what (got value)".
  void require(bool ok, std::string_view key, std::string_view what, double got);
  void require(bool ok, std::string_view key, std::string_view what, int got);
  /// Unless `ok`: "key what".
  void require(bool ok, std::string_view key, std::string_view what);

  /// A number as the messages print it.
  [[nodiscard]] static std::string format(double v);

 private:
  void add(std::string_view key, std::string_view what, const std::string& got);
  [[nodiscard]] std::string key(std::string_view k) const { return prefix_ + std::string(k); }

  std::vector<std::string>& out_;
  std::string prefix_;
};

}  // namespace overtake::core
