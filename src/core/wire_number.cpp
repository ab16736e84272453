#include "overtake/core/wire_number.hpp"

#include <charconv>
#include <cmath>
#include <system_error>

#include "overtake/core/telemetry.hpp"
#include "overtake/core/units.hpp"

namespace overtake::core {

double wire_round(double value) {
  if (!std::isfinite(value)) return value;
  const auto f = static_cast<float>(value);
  char buf[32];
  const auto printed = std::to_chars(buf, buf + sizeof buf, f, std::chars_format::general, 7);
  double out = 0.0;
  std::from_chars(buf, printed.ptr, out);
  return out;
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
