#pragma once
// The replay format's byte-level pieces, shared by the encoder, the writer and the reader
// (internal to the replay target): sizes and limits, little-endian fields, varints, fixed
// point, records.

#include <algorithm>
#include <bit>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "overtake/core/units.hpp"
#include "overtake/replay/replay.hpp"

namespace overtake::replay::wire {

inline constexpr double kCmPerM = 100.0;
inline constexpr double kYawUnitsPerRad = 1e4;
inline constexpr std::size_t kRecordHeadBytes = 5;   // u8 kind, u32 length
inline constexpr std::size_t kFrameFloatBytes = 36;  // f32 s, d, 4 strict figures, 3 distances
inline constexpr std::size_t kIncidentBytes = 18;
// Added within version 2 at the ends of records (older readers skip them):
inline constexpr std::size_t kFrameSafetyBytes = 6;     // u16 TTC ahead, TTC entering, headway
inline constexpr std::size_t kCollisionClassBytes = 2;  // u8 collision kind, u8 at fault
// After the class (added later within version 2): u32 the collision's contact, counting from 1
// (0: not a collision, or not known).
inline constexpr std::size_t kContactBytes = 4;
// At the end of a path record (added later within version 2, for runs of planners from
// outside): the points as the world reads them (wire-rounded), exactly. u32 n, u8 form, then
// form 1: 2n zigzag varints, each coordinate in units of 1e-4 m (a whole number: the rounded
// value is that decimal) less the same axis's of the point before (0 before the first);
// form 0: 2n u64, each coordinate's bits XOR those of the same axis's before.
inline constexpr std::size_t kExactHeadBytes = 5;
inline constexpr std::size_t kExactPointBytes = 16;  // form 0
inline constexpr double kExactUnitsPerM = 1e4;
inline constexpr std::int64_t kMaxExactStep = 10'000'000'000;  // fits a 5-byte zigzag varint

// The double a decimal count of 1e-4 m units reads as (nearest, as the wire's text is read).
inline double exact_of_units(std::int64_t units) {
  char buf[40];
  auto end = std::to_chars(buf, buf + sizeof buf - 4, units).ptr;
  for (const char c : std::string_view("e-4")) *end++ = c;
  double v = 0.0;
  std::from_chars(buf, end, v);
  return v;
}

// `v` as a count of 1e-4 m units when it reads back exactly from it.
inline std::optional<std::int64_t> units_of_exact(double v) {
  if (!(std::abs(v) < 1e9)) return std::nullopt;
  const auto units = static_cast<std::int64_t>(std::llround(v * kExactUnitsPerM));
  if (std::bit_cast<std::uint64_t>(exact_of_units(units)) != std::bit_cast<std::uint64_t>(v)) {
    return std::nullopt;
  }
  return units;
}
inline constexpr std::uint8_t kNoCollisionKind = 255;  // an incident that is not a collision
inline constexpr std::uint16_t kNoSeconds = 65535;     // TTC or headway: none (or >= 655.35 s)
inline constexpr std::size_t kMaxVarintBytes = 5;  // 35 bits: the zigzag of a difference of two i32
inline constexpr std::size_t kIdCount = 65536;     // car ids are u16
inline constexpr std::size_t kMaxCars = 255;
inline constexpr std::size_t kMaxPathPoints = 65535;
inline constexpr std::size_t kMaxRecordBytes = std::size_t{64} << 20;  // larger: corrupt
inline constexpr std::size_t kDeflateChunkBytes = std::size_t{64} << 10;
inline constexpr std::size_t kSyncEveryBytes = std::size_t{1} << 20;
inline constexpr std::size_t kInflateChunkBytes = std::size_t{256} << 10;
inline constexpr int kDeflateLevel =
    6;  // zlib's default: level 9 is 0.2 % smaller and twice as slow
inline constexpr const char* kUnfinishedReport =
    R"({"ended_early":"the recording stopped before the run's report"})";

// ---- little-endian fields -----------------------------------------------------------------

inline void put_u8(std::string& out, std::uint8_t v) {
  out.push_back(static_cast<char>(v));
}

inline void put_u16(std::string& out, std::uint16_t v) {
  out.push_back(static_cast<char>(v & 0xff));
  out.push_back(static_cast<char>(v >> 8));
}

inline void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

inline void put_i32(std::string& out, std::int32_t v) {
  put_u32(out, static_cast<std::uint32_t>(v));
}
inline void put_u64(std::string& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
inline void put_f32(std::string& out, double v) {
  put_u32(out, std::bit_cast<std::uint32_t>(static_cast<float>(v)));
}

// LEB128: 7 bits a byte, low first, the high bit set on every byte but the last.
inline void put_uvarint(std::string& out, std::uint64_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<char>((v & 0x7f) | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<char>(v));
}

// A signed difference, zigzagged (0, -1, 1, -2, ... -> 0, 1, 2, 3, ...) then LEB128.
inline void put_delta(std::string& out, std::int64_t now, std::int64_t before) {
  const std::int64_t d = now - before;
  put_uvarint(out, (static_cast<std::uint64_t>(d) << 1) ^ static_cast<std::uint64_t>(d >> 63));
}

using Fixed = ReplayEncoder::Fixed;
using FixedCar = ReplayEncoder::FixedCar;

// Where car `id` is in `cars` (ids unique), or -1; it is usually at `hint` (same order as in
// the frame before).
inline long find_car(const std::vector<FixedCar>& cars, int id, std::size_t hint) {
  if (hint < cars.size() && cars[hint].id == id) return static_cast<long>(hint);
  for (std::size_t j = 0; j < cars.size(); ++j) {
    if (cars[j].id == id) return static_cast<long>(j);
  }
  return -1;
}

// `v * scale` rounded and clamped to [lo, hi]; non-finite values become 0.
inline long long fixed(double v, double scale, long long lo, long long hi) {
  const double x = v * scale;
  if (!std::isfinite(x)) return 0;
  if (x <= static_cast<double>(lo)) return lo;
  if (x >= static_cast<double>(hi)) return hi;
  return std::llround(x);
}

inline std::int32_t cm(double m) {
  return static_cast<std::int32_t>(fixed(m, kCmPerM, INT32_MIN, INT32_MAX));
}
inline std::int16_t yaw_units(double rad) {
  return static_cast<std::int16_t>(
      fixed(core::wrap_angle_rad(rad), kYawUnitsPerRad, -32767, 32767));
}
inline std::uint16_t speed_cmps(double mps) {
  return static_cast<std::uint16_t>(fixed(mps, kCmPerM, 0, 65535));
}
// A TTC or headway in 0.01 s; none (infinity) and anything from 655.35 s on: kNoSeconds.
inline std::uint16_t centiseconds(double s) {
  if (!(s < kNoSeconds / 100.0)) return kNoSeconds;
  return static_cast<std::uint16_t>(fixed(s, 100.0, 0, kNoSeconds - 1));
}
inline double seconds_of(std::uint16_t cs) {
  return cs == kNoSeconds ? std::numeric_limits<double>::infinity() : cs / 100.0;
}

// Starts a record; returns where its length goes.
inline std::size_t begin_record(std::string& out, ReplayRecordKind kind) {
  put_u8(out, static_cast<std::uint8_t>(kind));
  const std::size_t at = out.size();
  put_u32(out, 0);
  return at;
}

inline void end_record(std::string& out, std::size_t length_at) {
  const auto n = static_cast<std::uint32_t>(out.size() - length_at - 4);
  for (int i = 0; i < 4; ++i) out[length_at + i] = static_cast<char>((n >> (8 * i)) & 0xff);
}

class Reader {
 public:
  explicit Reader(std::string_view bytes) : b_(bytes) {}
  [[nodiscard]] std::uint8_t u8() { return static_cast<std::uint8_t>(b_[at_++]); }
  [[nodiscard]] std::uint16_t u16() {
    const auto v = static_cast<std::uint16_t>(byte(0) | (byte(1) << 8));
    at_ += 2;
    return v;
  }
  [[nodiscard]] std::uint32_t u32() {
    const std::uint32_t v = byte(0) | (byte(1) << 8) | (byte(2) << 16) | (byte(3) << 24);
    at_ += 4;
    return v;
  }
  [[nodiscard]] std::uint64_t u64() {
    const std::uint64_t lo = u32();
    const std::uint64_t hi = u32();
    return lo | (hi << 32U);
  }
  [[nodiscard]] std::int16_t i16() { return static_cast<std::int16_t>(u16()); }
  [[nodiscard]] std::size_t remaining() const { return b_.size() - at_; }
  // An unsigned LEB128 varint of at most kMaxVarintBytes bytes; nullopt when the payload ends
  // inside it or it is longer (then overlong() is true).
  [[nodiscard]] std::optional<std::uint64_t> uvarint() {
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < kMaxVarintBytes && at_ < b_.size(); ++i) {
      const auto byte = static_cast<unsigned char>(b_[at_++]);
      v |= static_cast<std::uint64_t>(byte & 0x7f) << (7 * i);
      if (byte < 0x80) return v;
      if (i + 1 == kMaxVarintBytes) overlong_ = true;
    }
    return std::nullopt;
  }
  [[nodiscard]] bool overlong() const { return overlong_; }
  // A zigzag varint: a signed difference.
  [[nodiscard]] std::optional<std::int64_t> delta() {
    const auto z = uvarint();
    if (!z) return std::nullopt;
    return static_cast<std::int64_t>(*z >> 1) ^ -static_cast<std::int64_t>(*z & 1);
  }
  [[nodiscard]] std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  [[nodiscard]] double f32() { return static_cast<double>(std::bit_cast<float>(u32())); }
  [[nodiscard]] double metres() { return static_cast<double>(i32()) / kCmPerM; }

 private:
  [[nodiscard]] std::uint32_t byte(std::size_t i) const {
    return static_cast<unsigned char>(b_[at_ + i]);
  }
  std::string_view b_;
  std::size_t at_ = 0;
  bool overlong_ = false;
};

inline std::string incident_type_name(std::size_t i) {
  return std::string(sim::to_string(static_cast<sim::IncidentType>(i)));
}

}  // namespace overtake::replay::wire
