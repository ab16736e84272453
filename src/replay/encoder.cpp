// The record encoder: frames, paths, incidents and the end record (docs/replay.md).

#include "overtake/core/wire_number.hpp"
#include "wire.hpp"

namespace overtake::replay {

using namespace wire;

void ReplayEncoder::append_frame(const ReplayFrame& f, std::string& out) {
  const std::size_t at = begin_record(out, ReplayRecordKind::frame);
  put_u32(out, static_cast<std::uint32_t>(f.step));
  const Fixed e{cm(f.position.x), cm(f.position.y), yaw_units(f.yaw_rad), speed_cmps(f.speed_mps)};
  put_delta(out, e.x, ego_.x);
  put_delta(out, e.y, ego_.y);
  put_delta(out, e.yaw, ego_.yaw);
  put_delta(out, e.speed, ego_.speed);
  ego_ = e;
  put_f32(out, f.s_m);
  put_f32(out, f.d_m);
  put_f32(out, f.strict.tangential_mps2);
  put_f32(out, f.strict.normal_mps2);
  put_f32(out, f.strict.acceleration_mps2);
  put_f32(out, f.strict.jerk_mps3);
  put_f32(out, f.distance_m);
  put_f32(out, f.incident_free_m);
  put_f32(out, f.best_incident_free_m);

  // The cars, ids unique (the traffic's are: a repeat can only come from clamping).
  if (in_frame_.empty()) in_frame_.resize(kIdCount);
  next_.clear();
  for (const ReplayCar& c : f.cars) {
    if (next_.size() == kMaxCars) break;
    const int id = std::clamp(c.id, 0, static_cast<int>(kIdCount - 1));
    if (in_frame_[static_cast<std::size_t>(id)]) continue;
    in_frame_[static_cast<std::size_t>(id)] = true;
    next_.push_back(
        {id, {cm(c.position.x), cm(c.position.y), yaw_units(c.yaw_rad), speed_cmps(c.speed_mps)}});
  }
  base_.assign(next_.size(), Fixed{});
  for (std::size_t k = 0; k < next_.size(); ++k) {
    in_frame_[static_cast<std::size_t>(next_[k].id)] = false;
    const long j = find_car(cars_, next_[k].id, k);
    if (j >= 0) base_[k] = cars_[static_cast<std::size_t>(j)].at;  // else: from zero
  }
  put_u8(out, static_cast<std::uint8_t>(next_.size()));
  for (const FixedCar& c : next_) put_uvarint(out, static_cast<std::uint64_t>(c.id));
  for (std::size_t k = 0; k < next_.size(); ++k) put_delta(out, next_[k].at.x, base_[k].x);
  for (std::size_t k = 0; k < next_.size(); ++k) put_delta(out, next_[k].at.y, base_[k].y);
  for (std::size_t k = 0; k < next_.size(); ++k) put_delta(out, next_[k].at.yaw, base_[k].yaw);
  for (std::size_t k = 0; k < next_.size(); ++k) put_delta(out, next_[k].at.speed, base_[k].speed);
  put_u16(out, centiseconds(f.safety.ttc_ahead_s));
  put_u16(out, centiseconds(f.safety.ttc_entering_s));
  put_u16(out, centiseconds(f.safety.headway_s));
  cars_.swap(next_);
  end_record(out, at);
}

void ReplayEncoder::append_incidents(std::span<const sim::Incident> incidents,
                                     std::string& out) const {
  for (const sim::Incident& i : incidents) {
    const std::size_t iat = begin_record(out, ReplayRecordKind::incident);
    put_u8(out, static_cast<std::uint8_t>(i.type));
    // The report's units: speeding in mph.
    put_f32(out, i.type == sim::IncidentType::speeding ? core::mps_to_mph(i.value) : i.value);
    put_f32(out, i.s_m);
    put_u8(out, static_cast<std::uint8_t>(std::clamp(i.lane, 0, 255)));
    put_i32(out, ego_.x);  // where the ego is (this frame's)
    put_i32(out, ego_.y);
    put_u8(out, i.collision ? static_cast<std::uint8_t>(i.collision->kind) : kNoCollisionKind);
    put_u8(out, i.collision && i.collision->at_fault ? 1 : 0);
    put_u32(out, i.type == sim::IncidentType::collision && i.contact >= 0
                     ? static_cast<std::uint32_t>(i.contact) + 1U
                     : 0U);
    end_record(out, iat);
  }
}

void ReplayEncoder::append_path(std::span<const core::Vec2> path, std::string& out,
                                bool exact) const {
  const std::size_t count = std::min(path.size(), kMaxPathPoints);
  const std::size_t at = begin_record(out, ReplayRecordKind::path);
  put_u16(out, static_cast<std::uint16_t>(count));
  std::int32_t x = ego_.x;  // the first point against the ego, the others against the point before
  std::int32_t y = ego_.y;
  for (std::size_t i = 0; i < count; ++i) {
    const std::int32_t px = cm(path[i].x);
    const std::int32_t py = cm(path[i].y);
    put_delta(out, px, x);
    put_delta(out, py, y);
    x = px;
    y = py;
  }
  if (exact) {
    // The points as the world reads them: whole numbers of 1e-4 m when every one is (always,
    // for coordinates of 1 m to 1,000 km), else their bits.
    std::vector<std::int64_t> units;
    units.reserve(2 * count);
    for (std::size_t i = 0; i < count && units.size() == 2 * i; ++i) {
      for (const double v : {path[i].x, path[i].y}) {
        const auto u = units_of_exact(core::wire_round(v));
        const std::int64_t before = units.size() >= 2 ? units[units.size() - 2] : 0;
        if (!u || std::abs(*u - before) > kMaxExactStep) break;
        units.push_back(*u);
      }
    }
    put_u32(out, static_cast<std::uint32_t>(count));
    const bool decimal = units.size() == 2 * count;
    put_u8(out, decimal ? 1 : 0);
    if (decimal) {
      for (std::size_t k = 0; k < units.size(); ++k) {
        put_delta(out, units[k], k >= 2 ? units[k - 2] : 0);
      }
    } else {
      std::uint64_t bx = 0;
      std::uint64_t by = 0;
      for (std::size_t i = 0; i < count; ++i) {
        const auto nx = std::bit_cast<std::uint64_t>(core::wire_round(path[i].x));
        const auto ny = std::bit_cast<std::uint64_t>(core::wire_round(path[i].y));
        put_u64(out, nx ^ bx);
        put_u64(out, ny ^ by);
        bx = nx;
        by = ny;
      }
    }
  }
  end_record(out, at);
}

void ReplayEncoder::append_end(std::string_view report_json, std::string& out) {
  const std::size_t at = begin_record(out, ReplayRecordKind::end);
  out += report_json;
  end_record(out, at);
}

void ReplayEncoder::append_checkpoint(std::string_view encoded, std::string& out) {
  const std::size_t at = begin_record(out, ReplayRecordKind::checkpoint);
  out += encoded;
  end_record(out, at);
}

}  // namespace overtake::replay
