#include "overtake/core/param_check.hpp"

#include <cmath>
#include <sstream>

namespace overtake::core {

std::string ParamChecker::format(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

void ParamChecker::add(std::string_view k, std::string_view what, const std::string& got) {
  out_.push_back(key(k) + " " + std::string(what) + " (got " + got + ")");
}

void ParamChecker::positive(std::string_view k, double v) {
  if (!(v > 0.0) || !std::isfinite(v)) add(k, "must be a positive number", format(v));
}

void ParamChecker::non_negative(std::string_view k, double v) {
  if (!(v >= 0.0) || !std::isfinite(v)) add(k, "must be zero or more", format(v));
}

void ParamChecker::non_negative(std::string_view k, int v) {
  if (v < 0) add(k, "must be zero or more", std::to_string(v));
}

void ParamChecker::finite(std::string_view k, double v) {
  if (!std::isfinite(v)) out_.push_back(key(k) + " must be finite");
}

void ParamChecker::in_range(std::string_view k, double v, double lo, double hi) {
  if (!(v >= lo && v <= hi))
    add(k, "must be between " + format(lo) + " and " + format(hi), format(v));
}

void ParamChecker::in_range(std::string_view k, int v, int lo, int hi) {
  if (v < lo || v > hi) {
    add(k, "must be between " + std::to_string(lo) + " and " + std::to_string(hi),
        std::to_string(v));
  }
}

void ParamChecker::at_most(std::string_view k, double v, double limit, std::string_view limit_key) {
  if (v > limit) add(k, "must be at most " + std::string(limit_key), format(v));
}

void ParamChecker::at_least(std::string_view k, int v, int lo) {
  if (v < lo) add(k, "must be at least " + std::to_string(lo), std::to_string(v));
}

void ParamChecker::ordered(std::string_view lo_key, double lo, std::string_view hi_key, double hi) {
  if (lo > hi) {
    out_.push_back(key(lo_key) + " (" + format(lo) + ") must not exceed " + key(hi_key) + " (" +
                   format(hi) + ")");
  }
}

void ParamChecker::positive_list(std::string_view k, const std::vector<double>& v) {
  if (v.empty()) out_.push_back(key(k) + " must list at least one value");
  for (const double x : v) {
    if (!(x > 0.0) || !std::isfinite(x)) {
      add(k, "must hold positive numbers", format(x));
      break;
    }
  }
}

void ParamChecker::require(bool ok, std::string_view k, std::string_view what, double got) {
  if (!ok) add(k, what, format(got));
}

void ParamChecker::require(bool ok, std::string_view k, std::string_view what, int got) {
  if (!ok) add(k, what, std::to_string(got));
}

void ParamChecker::require(bool ok, std::string_view k, std::string_view what) {
  if (!ok) out_.push_back(key(k) + " " + std::string(what));
}

}  // namespace overtake::core
