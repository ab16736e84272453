#include "overtake/core/state_archive.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <utility>

namespace overtake::core {

StateArchive::StateArchive(std::string_view bytes, std::string name)
    : loading_(true), in_(bytes), name_(std::move(name)) {}

void StateArchive::fail(std::string_view what) const {
  std::string msg = name_.empty() ? std::string("state") : name_;
  msg += ": ";
  if (!part_.empty()) msg += "in part '" + part_ + "', ";
  msg += "at byte " + std::to_string(pos_) + ": " + std::string(what);
  throw StateError(msg);
}

void StateArchive::require(bool ok, std::string_view what) const {
  if (loading_ && !ok) fail(what);
}

void StateArchive::put(std::uint64_t bits, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    out_.push_back(static_cast<char>((bits >> (8 * i)) & 0xFFU));
  }
}

std::uint64_t StateArchive::get(std::size_t n, std::string_view what) {
  if (in_.size() - pos_ < n) {
    fail(std::string(what) + ": the state ends early (" + std::to_string(in_.size()) + " bytes)");
  }
  std::uint64_t bits = 0;
  for (std::size_t i = 0; i < n; ++i) {
    bits |= static_cast<std::uint64_t>(static_cast<unsigned char>(in_[pos_ + i])) << (8 * i);
  }
  pos_ += n;
  return bits;
}

void StateArchive::part(std::string_view tag) {
  if (!loading_) {
    put(tag.size(), 1);
    out_.append(tag);
    part_ = tag;
    return;
  }
  const std::size_t n = get(1, "part tag");
  if (n != tag.size() || in_.size() - pos_ < n || in_.substr(pos_, n) != tag) {
    fail("expected part '" + std::string(tag) + "'");
  }
  pos_ += n;
  part_ = tag;
}

void StateArchive::magic(std::string_view bytes, std::string_view what) {
  if (!loading_) {
    out_.append(bytes);
    return;
  }
  if (in_.size() - pos_ < bytes.size() || in_.substr(pos_, bytes.size()) != bytes) {
    fail("not " + std::string(what) + " (it does not start with " + std::string(bytes) + ")");
  }
  pos_ += bytes.size();
}

void StateArchive::io(bool& v, std::string_view what) {
  if (!loading_) {
    put(v ? 1 : 0, 1);
    return;
  }
  const std::uint64_t b = get(1, what);
  if (b > 1) fail(std::string(what) + ": not a flag (" + std::to_string(b) + ")");
  v = b == 1;
}

void StateArchive::io(std::int32_t& v, std::string_view what) {
  if (!loading_) {
    put(static_cast<std::uint32_t>(v), 4);
    return;
  }
  v = static_cast<std::int32_t>(static_cast<std::uint32_t>(get(4, what)));
}

void StateArchive::io(std::int64_t& v, std::string_view what) {
  if (!loading_) {
    put(static_cast<std::uint64_t>(v), 8);
    return;
  }
  v = static_cast<std::int64_t>(get(8, what));
}

void StateArchive::io(std::uint32_t& v, std::string_view what) {
  if (!loading_) {
    put(v, 4);
    return;
  }
  v = static_cast<std::uint32_t>(get(4, what));
}

void StateArchive::io(std::uint64_t& v, std::string_view what) {
  if (!loading_) {
    put(v, 8);
    return;
  }
  v = get(8, what);
}

void StateArchive::io(std::uint8_t& v, std::string_view what) {
  if (!loading_) {
    put(v, 1);
    return;
  }
  v = static_cast<std::uint8_t>(get(1, what));
}

void StateArchive::io(double& v, std::string_view what) {
  if (!loading_) {
    put(std::bit_cast<std::uint64_t>(v), 8);
    return;
  }
  v = std::bit_cast<double>(get(8, what));
  if (std::isnan(v) || (std::isfinite(v) && std::abs(v) > kMaxValue)) {
    fail(std::string(what) + ": " + std::to_string(v) + " is not a value a run holds");
  }
}

namespace {

void check_bound(const StateArchive& ar, double v, double limit, std::string_view what) {
  if (!std::isfinite(v) || std::abs(v) > limit) {
    ar.fail(std::string(what) + ": " + std::to_string(v) + " is outside +-" +
            std::to_string(limit));
  }
}

}  // namespace

void StateArchive::io_metres(double& v, std::string_view what) {
  io(v, what);
  if (loading_) check_bound(*this, v, kMaxMetres, what);
}

void StateArchive::io_speed(double& v, std::string_view what) {
  io(v, what);
  if (loading_) check_bound(*this, v, kMaxSpeed, what);
}

void StateArchive::io_delta(double& v, std::uint64_t& prev_bits, std::string_view what,
                            double limit) {
  std::uint64_t bits = loading_ ? 0 : std::bit_cast<std::uint64_t>(v) ^ prev_bits;
  io(bits, what);
  bits ^= prev_bits;
  if (loading_) {
    v = std::bit_cast<double>(bits);
    if (std::isnan(v) || (std::isfinite(v) && std::abs(v) > limit)) {
      fail(std::string(what) + ": " + std::to_string(v) + " is outside +-" + std::to_string(limit));
    }
  }
  prev_bits = bits;
}

void StateArchive::io(Vec2& v, std::string_view what) {
  io_metres(v.x, what);
  io_metres(v.y, what);
}

void StateArchive::io(FrenetPoint& v, std::string_view what) {
  io_metres(v.s_m, what);
  io_metres(v.d_m, what);
}

void StateArchive::io(Rng& v, std::string_view what) {
  std::array<std::uint64_t, 4> s = v.state();
  for (std::uint64_t& w : s) io(w, what);
  if (!loading_) return;
  if (reseeding_) {
    v = Rng(derive_seed(reseed_, generators_++));
  } else {
    v.set_state(s);
  }
}

void StateArchive::io(std::string& v, std::size_t max_bytes, std::string_view what) {
  const std::size_t n = io_length(v.size(), max_bytes, what);
  if (!loading_) {
    out_.append(v);
    return;
  }
  if (in_.size() - pos_ < n) fail(std::string(what) + ": the state ends early");
  v.assign(in_.substr(pos_, n));
  pos_ += n;
}

void StateArchive::io_range(std::int32_t& v, std::int32_t lo, std::int32_t hi,
                            std::string_view what) {
  io(v, what);
  if (loading_ && (v < lo || v > hi)) {
    fail(std::string(what) + ": " + std::to_string(v) + " is outside [" + std::to_string(lo) +
         ", " + std::to_string(hi) + "]");
  }
}

void StateArchive::io_range(std::int64_t& v, std::int64_t lo, std::int64_t hi,
                            std::string_view what) {
  io(v, what);
  if (loading_ && (v < lo || v > hi)) {
    fail(std::string(what) + ": " + std::to_string(v) + " is outside [" + std::to_string(lo) +
         ", " + std::to_string(hi) + "]");
  }
}

void StateArchive::io_range(std::size_t& v, std::size_t lo, std::size_t hi, std::string_view what) {
  std::uint64_t raw = v;
  io(raw, what);
  if (loading_ && (raw < lo || raw > hi)) {
    fail(std::string(what) + ": " + std::to_string(raw) + " is outside [" + std::to_string(lo) +
         ", " + std::to_string(hi) + "]");
  }
  v = static_cast<std::size_t>(raw);
}

std::size_t StateArchive::io_length(std::size_t n, std::size_t max, std::string_view what) {
  std::size_t v = n;
  io_range(v, 0, max, std::string(what) + " (count)");
  return v;
}

void StateArchive::expect_end() const {
  if (loading_ && pos_ != in_.size()) {
    fail(std::to_string(in_.size() - pos_) + " bytes left over after the state");
  }
}

}  // namespace overtake::core
