#include "overtake/core/wire_number.hpp"

#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <system_error>

#include "overtake/core/telemetry.hpp"
#include "overtake/core/units.hpp"

namespace overtake::core {

namespace {

// What the text says: the float printed with 7 significant digits, read back as a double.
double wire_round_by_text(float f) {
  char buf[32];
  const auto printed = std::to_chars(buf, buf + sizeof buf, f, std::chars_format::general, 7);
  double out = 0.0;
  std::from_chars(buf, printed.ptr, out);
  return out;
}

// 10^k for k in [0, 22]: each exact in a double.
constexpr std::array<double, 23> kPowersOfTen = [] {
  std::array<double, 23> p{};
  double v = 1.0;
  for (double& x : p) {
    x = v;
    v *= 10.0;
  }
  return p;
}();

// 5^k for k in [0, 22] (below 2^52).
constexpr std::array<std::uint64_t, 23> kPowersOfFive = [] {
  std::array<std::uint64_t, 23> p{};
  std::uint64_t v = 1;
  for (std::uint64_t& x : p) {
    x = v;
    v *= 5;
  }
  return p;
}();

// 128-bit integers (GCC and Clang): the exact products below need 76 bits.
__extension__ using U128 = unsigned __int128;

/// n / 2^s rounded to the nearest integer, ties to even (as the printing rounds), for s >= 1.
template <class U>
U shift_right_to_even(U n, int s) {
  const U q = n >> s;
  const U rest = n - (q << s);
  const U half = static_cast<U>(1) << (s - 1);
  return rest > half || (rest == half && (q & 1U) != 0) ? q + 1 : q;
}

}  // namespace

double wire_round(double value) {
  if (!std::isfinite(value)) return value;
  const auto f = static_cast<float>(value);
  const auto abs_bits = std::bit_cast<std::uint32_t>(f) & 0x7FFFFFFFU;
  // The same number without text, for 1e-16 <= |f| < 1e6 (every figure of a run): the float
  // is M * 2^E exactly; times 10^k it is N * 2^(E + k) with N = M * 5^k, which is rounded to
  // the integer m of 7 digits (ties to even, as the printing does); m and 10^k are exact
  // doubles, so m / 10^k is the double nearest the printed decimal, which is what reading it
  // gives. Elsewhere (tiny or huge): the text.
  if (abs_bits == 0) return static_cast<double>(f);  // "0" or "-0"
  const float a = std::bit_cast<float>(abs_bits);
  if (!(a >= 1e-16F && a < 1e6F)) return wire_round_by_text(f);
  // a = m24 * 2^e2 exactly (a is a normal float here).
  const std::uint64_t m24 = (abs_bits & 0x7FFFFFU) | 0x800000U;
  const int e2 = static_cast<int>(abs_bits >> 23U) - 127 - 23;
  // The decimal exponent d with 10^d <= a < 10^(d + 1): log2(a) is in [e2 + 23, e2 + 24), so
  // d is floor((e2 + 23) * log10(2)) or one more. (x * 1233) >> 12 is floor(x * log10(2)) for
  // every |x| < 200 (here -54 <= x < 20), without a call to floor.
  int d = ((e2 + 23) * 1233) >> 12;
  const auto at_least_ten_to = [&](int p) {  // a >= 10^p (exact: 10^p is not a float)
    return p >= 0 ? static_cast<double>(a) >= kPowersOfTen[static_cast<std::size_t>(p)]
                  : static_cast<double>(a) * kPowersOfTen[static_cast<std::size_t>(-p)] >= 1.0;
  };
  if (at_least_ten_to(d + 1)) ++d;
  const int k = 6 - d;  // in [1, 22]
  if (k < 0 || k > 22) return wire_round_by_text(f);
  const int shift = e2 + k;
  std::uint64_t m = 0;
  if (k <= 16 && shift < 0 && shift > -64) {
    // The common case (|f| >= 1e-10, and in this range always a right shift): N < 2^24 * 5^16
    // < 2^62, so 64 bits hold it.
    m = shift_right_to_even(m24 * kPowersOfFive[static_cast<std::size_t>(k)], -shift);
  } else {
    // The same in 128-bit integers: the products need up to 76 bits.
    const U128 n = static_cast<U128>(m24) * kPowersOfFive[static_cast<std::size_t>(k)];
    if (shift >= 0) {
      m = static_cast<std::uint64_t>(n << shift);
    } else if (-shift < 127) {
      m = static_cast<std::uint64_t>(shift_right_to_even(n, -shift));
    } else {
      return wire_round_by_text(f);
    }
  }
  const double out = static_cast<double>(m) / kPowersOfTen[static_cast<std::size_t>(k)];
  return f < 0.0F ? -out : out;
}

namespace {

Vec2 round_vec(Vec2 v) {
  return {wire_round(v.x), wire_round(v.y)};
}

}  // namespace

Telemetry round_like_wire(Telemetry t) {
  t.ego.position = round_vec(t.ego.position);
  t.ego.yaw_rad = deg_to_rad(wire_round(rad_to_deg(t.ego.yaw_rad)));
  t.ego.speed_mps = mph_to_mps(wire_round(mps_to_mph(t.ego.speed_mps)));
  t.ego.s_m = wire_round(t.ego.s_m);
  t.ego.d_m = wire_round(t.ego.d_m);
  t.previous_path = round_like_wire(std::move(t.previous_path));
  t.end_path = {wire_round(t.end_path.s_m), wire_round(t.end_path.d_m)};
  for (auto& c : t.cars) {
    c.position = round_vec(c.position);
    c.velocity_mps = round_vec(c.velocity_mps);
    c.s_m = wire_round(c.s_m);
    c.d_m = wire_round(c.d_m);
  }
  return t;
}

std::vector<Vec2> round_like_wire(std::vector<Vec2> path) {
  for (auto& p : path) p = round_vec(p);
  return path;
}

}  // namespace overtake::core
