#pragma once
// The state of a run's parts as bytes: one class both writes and reads, so that each part
// lists its fields once (`archive(StateArchive&)`) and saving and restoring cannot drift
// apart. Values are fixed-width little-endian (doubles bit for bit), so the same state gives
// the same bytes on every machine. Reading checks everything as it goes: a truncated or
// damaged state is reported as a StateError naming the bytes, the part and the field, and
// never reaches the simulator as an out-of-range index or an absurd length.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/random.hpp"

namespace overtake::core {

/// Bytes that do not hold a valid state; the message names them, the part and the field.
class StateError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class StateArchive {
 public:
  static constexpr double kMaxValue = 1e10;
  static constexpr double kMaxMetres = 1e8;
  static constexpr double kMaxSpeed = 1e3;

  /// An archive that writes (take() returns the bytes).
  StateArchive() = default;
  /// An archive that reads `bytes` (which must outlive it); `name` names them in errors.
  StateArchive(std::string_view bytes, std::string name);

  [[nodiscard]] bool loading() const { return loading_; }
  /// Reading: every random generator read from now on is given a fresh state instead of the
  /// stored one, the n-th from derive_seed(seed, n) (a branch of a run: the world as it was,
  /// its future random draws new; docs/evaluation.md, "Rare events"). Writing: no effect.
  void reseed_generators(std::uint64_t seed) {
    reseed_ = seed;
    reseeding_ = true;
    generators_ = 0;
  }

  /// A named part: writing puts its tag; reading checks that the tag is there, so that a
  /// state written by another part's code is caught where it starts.
  void part(std::string_view tag);
  /// Bytes that open a file of a kind (no length before them); reading, `what` names the
  /// kind when they are not there.
  void magic(std::string_view bytes, std::string_view what);

  void io(bool& v, std::string_view what);
  void io(std::int32_t& v, std::string_view what);
  void io(std::int64_t& v, std::string_view what);
  void io(std::uint32_t& v, std::string_view what);
  void io(std::uint64_t& v, std::string_view what);
  void io(std::uint8_t& v, std::string_view what);
  /// A double: infinite (a sentinel) or finite within kMaxValue; never NaN.
  void io(double& v, std::string_view what);
  /// A length or coordinate: finite, within kMaxMetres (10^5 km: beyond any run's reach, and
  /// small enough that lane numbers and indices computed from it stay in range).
  void io_metres(double& v, std::string_view what);
  /// A speed (m/s) or a rate of a length: finite, within kMaxSpeed.
  void io_speed(double& v, std::string_view what);
  void io(Vec2& v, std::string_view what);
  void io(FrenetPoint& v, std::string_view what);
  void io(Rng& v, std::string_view what);
  /// A double of a series (the states along a path, a window of samples): stored as its bits
  /// XOR `prev_bits`, the bits of the series' value before it (0 for the first), which then
  /// become this value's. Neighbours share their high bytes, so the stored bytes compress.
  void io_delta(double& v, std::uint64_t& prev_bits, std::string_view what,
                double limit = kMaxValue);
  /// At most `max_bytes` bytes.
  void io(std::string& v, std::size_t max_bytes, std::string_view what);
  /// An index or count that must lie in [lo, hi] when read.
  void io_range(std::int32_t& v, std::int32_t lo, std::int32_t hi, std::string_view what);
  void io_range(std::int64_t& v, std::int64_t lo, std::int64_t hi, std::string_view what);
  void io_range(std::size_t& v, std::size_t lo, std::size_t hi, std::string_view what);
  /// An enum whose values are 0 .. `last`.
  template <class E>
  requires std::is_enum_v<E>
  void io_enum(E& v, E last, std::string_view what) {
    auto raw = static_cast<std::int64_t>(v);
    io_range(raw, 0, static_cast<std::int64_t>(last), what);
    v = static_cast<E>(raw);
  }

  /// A length: written as it is; read, at most `max` (an error names `what` otherwise).
  [[nodiscard]] std::size_t io_length(std::size_t n, std::size_t max, std::string_view what);

  /// A vector of at most `max` elements, each through `each(ar, element)`.
  template <class T, class F>
  void io_vector(std::vector<T>& v, std::size_t max, std::string_view what, F&& each) {
    const std::size_t n = io_length(v.size(), max, what);
    if (loading_) v.assign(n, T{});
    for (T& x : v) each(*this, x);
  }
  /// A vector of values io() takes.
  template <class T>
  void io_vector(std::vector<T>& v, std::size_t max, std::string_view what) {
    io_vector(v, max, what, [what](StateArchive& ar, T& x) { ar.io(x, what); });
  }
  template <class T>
  void io_deque(std::deque<T>& v, std::size_t max, std::string_view what) {
    const std::size_t n = io_length(v.size(), max, what);
    if (loading_) v.assign(n, T{});
    for (T& x : v) io(x, what);
  }
  /// An optional: a flag, then the value through `each(ar, value)`.
  template <class T, class F>
  void io_optional(std::optional<T>& o, std::string_view what, F&& each) {
    bool has = o.has_value();
    io(has, what);
    if (loading_) {
      if (has) {
        o.emplace(T{});
      } else {
        o.reset();
      }
    }
    if (has) each(*this, *o);
  }

  /// Reading: fails (StateError naming `what`) unless `ok`. Writing: does nothing (the
  /// writer's own state is trusted).
  void require(bool ok, std::string_view what) const;
  /// The bytes written so far.
  [[nodiscard]] const std::string& bytes() const { return out_; }
  [[nodiscard]] std::string take() { return std::move(out_); }
  /// Reading: fails unless every byte was read.
  void expect_end() const;
  /// Reading: every byte was read (a part added to a format later may be missing from bytes
  /// written before it).
  [[nodiscard]] bool at_end() const { return loading_ && pos_ >= in_.size(); }
  /// Bytes read or written so far.
  [[nodiscard]] std::size_t offset() const { return loading_ ? pos_ : out_.size(); }
  /// A StateError naming the bytes, the part and `what`.
  [[noreturn]] void fail(std::string_view what) const;

 private:
  void put(std::uint64_t bits, std::size_t n);
  [[nodiscard]] std::uint64_t get(std::size_t n, std::string_view what);

  bool loading_ = false;
  bool reseeding_ = false;
  std::uint64_t reseed_ = 0;
  std::uint64_t generators_ = 0;  // generators read since reseed_generators
  std::string out_;
  std::string_view in_;
  std::size_t pos_ = 0;
  std::string name_;
  std::string part_;
};

}  // namespace overtake::core
