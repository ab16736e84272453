// The checking reader: inflates and decodes a replay, saying what is wrong and where.

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <limits>
#include <utility>

#include <nlohmann/json.hpp>

#include "overtake/core/text_check.hpp"
#include "wire.hpp"

namespace overtake::replay {

using nlohmann::json;
using namespace wire;

namespace {

// What the decoder hands its visitor.
struct Sink {
  virtual ~Sink() = default;
  virtual void header(ReplayHeader h, std::string text) = 0;
  virtual void frame(const ReplayFrame& f) = 0;
  virtual void path(ReplayPath&& p) = 0;
  virtual void incident(const ReplayIncident& i) = 0;
  virtual void end(std::string text) = 0;
  virtual void unknown() = 0;
  virtual void checkpoint(ReplayCheckpoint&& c) = 0;
};

template <class T>
T header_value(const json& j, const char* key, const char* where) {
  try {
    return j.at(key).get<T>();
  } catch (const json::exception&) {
    throw std::invalid_argument(std::string("missing or wrong key '") + where + key + "'");
  }
}

// An integer key of the header: a JSON integer that fits T. get<T>() alone would truncate a
// fraction, wrap a negative seed, and convert a number beyond T (lanes: 1e300) with undefined
// behaviour.
template <class T>
T header_integer(const json& j, const char* key, const char* where) {
  const auto v = header_value<json>(j, key, where);
  const std::string name = std::string("'") + where + key + "'";
  if (!v.is_number()) throw std::invalid_argument(name + " is not an integer");
  const bool fits = v.is_number_unsigned()  ? std::in_range<T>(v.get<std::uint64_t>())
                    : v.is_number_integer() ? std::in_range<T>(v.get<std::int64_t>())
                                            : false;
  if (!fits)
    throw std::invalid_argument(name + " is " + v.dump() + ", not an integer within range");
  return v.get<T>();
}

ReplayHeader parse_header(const json& j) {
  ReplayHeader h;
  if (!j.is_object()) throw std::invalid_argument("not a JSON object");
  if (header_value<std::string>(j, "format", "") != "overtake-replay") {
    throw std::invalid_argument("'format' is not \"overtake-replay\"");
  }
  h.step_s = header_value<double>(j, "step_s", "");
  if (!(h.step_s > 0.0)) throw std::invalid_argument("'step_s' must be positive");
  const json& road = j.at("road");
  h.lanes = header_integer<int>(road, "lanes", "road.");
  h.lane_width_m = header_value<double>(road, "lane_width_m", "road.");
  const json& car = j.at("car");
  h.car_length_m = header_value<double>(car, "length_m", "car.");
  h.car_width_m = header_value<double>(car, "width_m", "car.");
  const json& limits = j.at("limits");
  h.speed_limit_mps = header_value<double>(limits, "speed_mps", "limits.");
  h.max_acceleration_mps2 = header_value<double>(limits, "acceleration_mps2", "limits.");
  h.max_jerk_mps3 = header_value<double>(limits, "jerk_mps3", "limits.");
  h.track_length_m = header_value<double>(j, "track_length_m", "");
  h.lane_lines = header_value<std::vector<std::vector<double>>>(j, "lane_lines", "");
  h.incident_types = header_value<std::vector<std::string>>(j, "incident_types", "");
  if (j.contains("collision_kinds")) {
    h.collision_kinds = header_value<std::vector<std::string>>(j, "collision_kinds", "");
  }
  const json& p = j.at("provenance");
  h.provenance.policy = header_value<std::string>(p, "policy", "provenance.");
  h.provenance.traffic = header_value<std::string>(p, "traffic", "provenance.");
  h.provenance.seed = header_integer<std::uint64_t>(p, "seed", "provenance.");
  h.provenance.track = header_value<std::string>(p, "track", "provenance.");
  h.provenance.duration_s = header_value<double>(p, "duration_s", "provenance.");
  h.provenance.overtake_version = header_value<std::string>(p, "overtake_version", "provenance.");
  h.provenance.config_hash = header_value<std::string>(p, "config_hash", "provenance.");
  if (p.contains("cut_from")) {  // added within version 2
    const json& c = p.at("cut_from");
    ReplayCutOrigin o;
    o.scenario = header_value<std::string>(c, "scenario", "provenance.cut_from.");
    o.replay = header_value<std::string>(c, "replay", "provenance.cut_from.");
    o.policy = header_value<std::string>(c, "policy", "provenance.cut_from.");
    o.traffic = header_value<std::string>(c, "traffic", "provenance.cut_from.");
    o.seed = header_integer<std::uint64_t>(c, "seed", "provenance.cut_from.");
    o.at_s = header_value<double>(c, "at_s", "provenance.cut_from.");
    o.start_s = header_value<double>(c, "start_s", "provenance.cut_from.");
    o.incident = header_value<std::string>(c, "incident", "provenance.cut_from.");
    h.provenance.cut_from = std::move(o);
  }
  return h;
}

std::string kind_name(std::uint8_t kind) {
  switch (kind) {
    case 1:
      return "frame";
    case 2:
      return "path";
    case 3:
      return "incident";
    case 4:
      return "end";
    case 5:
      return "checkpoint";
    default:
      return "kind " + std::to_string(kind);
  }
}

// Decodes bytes into the sink; throws ReplayError at the first fault. `state` tells the
// caller how far it got.
struct DecodeState {
  std::size_t records = 0;
  std::optional<long> last_step;
  double step_s = 0.02;
};

class Decoder {
 public:
  Decoder(std::string_view bytes, std::string_view name, Sink& sink, DecodeState& state)
      : bytes_(bytes), name_(name), sink_(sink), st_(state) {}

  void run() {
    preamble();
    body();
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw ReplayError(std::string(name_) + ": " + what);
  }

  // Where the last good record left off, for messages.
  [[nodiscard]] std::string after_text() const {
    if (st_.records == 0) return "before the first record";
    std::string s = "after record #" + std::to_string(st_.records);
    if (st_.last_step) {
      char buf[64];
      std::snprintf(buf, sizeof buf, " (step %ld, t = %.2f s)", *st_.last_step,
                    static_cast<double>(*st_.last_step) * st_.step_s);
      s += buf;
    }
    return s;
  }

  void preamble() {
    const std::size_t n = bytes_.size();
    const std::size_t magic_n = std::min(n, kReplayMagic.size());
    if (n == 0) fail("not an overtake replay: the file is empty");
    if (bytes_.substr(0, magic_n) != kReplayMagic.substr(0, magic_n)) {
      fail("not an overtake replay: it does not start with \"OVTKRPLY\"");
    }
    if (n < kReplayPreambleBytes) {
      fail("truncated: the file ends at byte " + std::to_string(n) + ", inside its " +
           std::to_string(kReplayPreambleBytes) + "-byte preamble");
    }
    Reader r(bytes_.substr(8, 8));
    const std::uint32_t version = r.u32();
    const std::uint32_t header_bytes = r.u32();
    if (version == 1) {
      fail("replay format version 1 is not supported (this build reads version " +
           std::to_string(kReplayVersion) + "); re-record the run with this build");
    }
    if (version != kReplayVersion) {
      fail("replay format version " + std::to_string(version) + "; this build reads version " +
           std::to_string(kReplayVersion) + " (see docs/replay.md)");
    }
    if (header_bytes > n - kReplayPreambleBytes) {
      fail("truncated: the header is " + std::to_string(header_bytes) +
           " bytes but the file ends at byte " + std::to_string(n));
    }
    body_start_ = kReplayPreambleBytes + header_bytes;
    std::string text(bytes_.substr(kReplayPreambleBytes, header_bytes));
    ReplayHeader h;
    try {
      core::require_json_depth(text, "its JSON");
      h = parse_header(json::parse(text));
    } catch (const std::exception& e) {
      fail("corrupt header (bytes 16-" + std::to_string(body_start_) + "): " + e.what());
    }
    st_.step_s = h.step_s;
    incident_types_ = h.incident_types.size();
    const auto collision = std::find(h.incident_types.begin(), h.incident_types.end(), "collision");
    collision_type_ = collision == h.incident_types.end()
                          ? -1
                          : static_cast<int>(collision - h.incident_types.begin());
    collision_kinds_ = std::min(h.collision_kinds.size(), sim::kCollisionKindCount);
    sink_.header(std::move(h), std::move(text));
  }

  void body() {
    if (body_start_ == bytes_.size()) {
      fail("truncated: the file ends after its header, with no records (at byte " +
           std::to_string(body_start_) + ")");
    }
    z_stream z{};
    if (inflateInit(&z) != Z_OK) fail("cannot start the decompressor (zlib)");
    struct End {
      z_stream& z;
      ~End() { inflateEnd(&z); }
    } end{z};
    const std::string_view in = bytes_.substr(body_start_);
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
    z.avail_in = static_cast<uInt>(std::min<std::size_t>(in.size(), UINT_MAX));
    std::size_t fed = z.avail_in;
    std::string buf;
    std::size_t used = 0;  // bytes of buf already parsed
    bool stream_end = false;
    while (!stream_end) {
      const std::size_t old = buf.size();
      buf.resize(old + kInflateChunkBytes);
      z.next_out = reinterpret_cast<Bytef*>(buf.data() + old);
      z.avail_out = static_cast<uInt>(kInflateChunkBytes);
      const int rc = inflate(&z, Z_NO_FLUSH);
      buf.resize(old + kInflateChunkBytes - z.avail_out);
      if (rc == Z_STREAM_END) {
        stream_end = true;
      } else if (rc == Z_DATA_ERROR && z.msg && std::string_view(z.msg) == "incorrect data check") {
        parse_records(buf, used);
        fail("corrupt: the checksum at the end of the compressed body does not match, so bytes " +
             std::to_string(body_start_) + "-" + std::to_string(bytes_.size()) +
             " were damaged somewhere (the records decoded may hold wrong values), " +
             after_text());
      } else if (rc == Z_DATA_ERROR || rc == Z_NEED_DICT) {
        fail("corrupt: the compressed body is damaged near byte " +
             std::to_string(body_start_ + z.total_in) +
             " (zlib: " + (z.msg ? z.msg : "data error") + "), " + after_text());
      } else if (rc == Z_MEM_ERROR) {
        fail("out of memory while decompressing");
      } else if (rc == Z_BUF_ERROR || (rc == Z_OK && z.avail_in == 0 && z.avail_out != 0)) {
        if (z.avail_in == 0 && fed < in.size()) {  // more than 4 GiB of body: feed the rest
          const std::size_t more = std::min<std::size_t>(in.size() - fed, UINT_MAX);
          z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data() + fed));
          z.avail_in = static_cast<uInt>(more);
          fed += more;
        } else if (z.avail_in == 0) {
          parse_records(buf, used);
          fail("truncated: the compressed body stops at byte " + std::to_string(bytes_.size()) +
               " before its end, " + after_text());
        }
      }
      parse_records(buf, used);
      if (used > (std::size_t{1} << 20) && used * 2 > buf.size()) {
        buf.erase(0, used);
        inflated_base_ += used;
        used = 0;
      }
    }
    if (used != buf.size()) {
      fail("corrupt: the body ends inside record #" + std::to_string(st_.records + 1) +
           " (at inflated byte " + std::to_string(inflated_base_ + used) + "), " + after_text());
    }
    const std::size_t trailing = z.avail_in + (in.size() - fed);
    if (trailing > 0) {
      fail("corrupt: " + std::to_string(trailing) +
           " unexpected bytes after the compressed body (from byte " +
           std::to_string(bytes_.size() - trailing) + ")");
    }
    if (!ended_) fail("truncated: no end record, " + after_text());
  }

  void parse_records(const std::string& buf, std::size_t& used) {
    while (buf.size() - used >= kRecordHeadBytes) {
      Reader head(std::string_view(buf).substr(used, kRecordHeadBytes));
      const std::uint8_t kind = head.u8();
      const std::uint32_t n = head.u32();
      if (n > kMaxRecordBytes) {
        fail("corrupt: record #" + std::to_string(st_.records + 1) + " (" + kind_name(kind) +
             ", at inflated byte " + std::to_string(inflated_base_ + used) + ") claims " +
             std::to_string(n) + " bytes, " + after_text());
      }
      if (buf.size() - used - kRecordHeadBytes < n) return;  // not complete yet
      record(kind, std::string_view(buf).substr(used + kRecordHeadBytes, n), inflated_base_ + used);
      used += kRecordHeadBytes + n;
      ++st_.records;
    }
  }

  [[noreturn]] void bad_record(std::uint8_t kind, std::size_t at, const std::string& what) const {
    fail("corrupt: record #" + std::to_string(st_.records + 1) + " (" + kind_name(kind) +
         ", at inflated byte " + std::to_string(at) + "): " + what + ", " + after_text());
  }

  // `v` when it lies in [lo, hi], else the record is corrupt (`who`'s `what` is out of range).
  std::int64_t in_range(std::uint8_t kind, std::size_t at, std::int64_t v, std::int64_t lo,
                        std::int64_t hi, const char* who, const char* what) const {
    if (v < lo || v > hi) {
      bad_record(kind, at,
                 std::string(who) + "'s " + what + " comes to " + std::to_string(v) +
                     ", outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
    return v;
  }

  // A varint of `what` could not be read.
  [[noreturn]] void bad_varint(std::uint8_t kind, std::size_t at, const Reader& r,
                               const std::string& what, std::size_t payload_bytes) const {
    bad_record(kind, at,
               what + (r.overlong() ? " hold a varint longer than " +
                                          std::to_string(kMaxVarintBytes) + " bytes"
                                    : " run past the end of the " + std::to_string(payload_bytes) +
                                          "-byte payload"));
  }

  // The ego's x, y, yaw and speed as differences from the frame before (zigzag varints).
  Fixed ego_after(std::uint8_t kind, std::size_t at, Reader& r, std::size_t payload_bytes) const {
    std::int64_t d[4];
    for (std::int64_t& v : d) {
      const auto got = r.delta();
      if (!got) bad_varint(kind, at, r, "the ego's position and speed", payload_bytes);
      v = *got;
    }
    constexpr const char* kEgo = "the ego";
    Fixed f;
    f.x = static_cast<std::int32_t>(
        in_range(kind, at, ego_.x + d[0], INT32_MIN, INT32_MAX, kEgo, "x"));
    f.y = static_cast<std::int32_t>(
        in_range(kind, at, ego_.y + d[1], INT32_MIN, INT32_MAX, kEgo, "y"));
    f.yaw = static_cast<std::int32_t>(
        in_range(kind, at, ego_.yaw + d[2], INT16_MIN, INT16_MAX, kEgo, "yaw"));
    f.speed = static_cast<std::int32_t>(
        in_range(kind, at, ego_.speed + d[3], 0, UINT16_MAX, kEgo, "speed"));
    return f;
  }

  // A frame's `count` cars into next_: ids, then the columns of differences from the same
  // car in the frame before (from zero for a car that was not in it).
  void cars_after(std::uint8_t kind, std::size_t at, Reader& r, std::size_t count,
                  std::size_t payload_bytes) {
    const auto what = [count](const char* column) {
      return std::string("the ") + column + " of its " + std::to_string(count) + " cars";
    };
    if (in_frame_.empty()) in_frame_.resize(kIdCount);
    next_.resize(count);
    base_.assign(count, Fixed{});
    for (std::size_t k = 0; k < count; ++k) {
      const auto id = r.uvarint();
      if (!id) bad_varint(kind, at, r, what("ids"), payload_bytes);
      if (*id >= kIdCount)
        bad_record(kind, at, "car id " + std::to_string(*id) + " is above 65535");
      // A repeated id is corrupt (the decoder stops, so its marks need no clearing).
      if (in_frame_[*id]) bad_record(kind, at, "car id " + std::to_string(*id) + " appears twice");
      in_frame_[*id] = true;
      next_[k].id = static_cast<int>(*id);
    }
    for (std::size_t k = 0; k < count; ++k) {
      in_frame_[static_cast<std::size_t>(next_[k].id)] = false;
      const long j = find_car(cars_, next_[k].id, k);
      if (j >= 0) base_[k] = cars_[static_cast<std::size_t>(j)].at;  // else: from zero
    }
    const auto column = [&](const char* name, std::int32_t Fixed::*field, std::int64_t lo,
                            std::int64_t hi) {
      for (std::size_t k = 0; k < count; ++k) {
        const auto d = r.delta();
        if (!d) bad_varint(kind, at, r, what(name), payload_bytes);
        next_[k].at.*field = static_cast<std::int32_t>(
            in_range(kind, at, base_[k].*field + *d, lo, hi, "a car", name));
      }
    };
    column("x", &Fixed::x, INT32_MIN, INT32_MAX);
    column("y", &Fixed::y, INT32_MIN, INT32_MAX);
    column("yaw", &Fixed::yaw, INT16_MIN, INT16_MAX);
    column("speed", &Fixed::speed, 0, UINT16_MAX);
  }

  // Throws the record's error when its payload is shorter than `bytes`.
  void need(std::uint8_t kind, std::size_t at, std::string_view p, std::size_t bytes) const {
    if (p.size() < bytes) {
      bad_record(
          kind, at,
          std::to_string(p.size()) + " bytes where " + std::to_string(bytes) + " are needed");
    }
  }

  void record(std::uint8_t kind, std::string_view p, std::size_t at) {
    if (ended_) bad_record(kind, at, "a record after the end record");
    Reader r(p);
    switch (kind) {
      case static_cast<std::uint8_t>(ReplayRecordKind::frame):
        return frame_record(kind, p, at, r);
      case static_cast<std::uint8_t>(ReplayRecordKind::path):
        return path_record(kind, p, at, r);
      case static_cast<std::uint8_t>(ReplayRecordKind::incident):
        return incident_record(kind, p, at, r);
      case static_cast<std::uint8_t>(ReplayRecordKind::checkpoint):
        return checkpoint_record(kind, p, at);
      case static_cast<std::uint8_t>(ReplayRecordKind::end):
        return end_record(kind, p, at);
      default:
        sink_.unknown();
        return;
    }
  }

  void frame_record(std::uint8_t kind, std::string_view p, std::size_t at, Reader& r) {
    need(kind, at, p, 4);
    ReplayFrame& f = frame_;
    f.step = static_cast<long>(r.u32());
    if (st_.last_step && f.step <= *st_.last_step) {
      bad_record(kind, at,
                 "step " + std::to_string(f.step) + " does not follow step " +
                     std::to_string(*st_.last_step));
    }
    const Fixed e = ego_after(kind, at, r, p.size());
    need(kind, at, p, p.size() - r.remaining() + kFrameFloatBytes + 1);
    f.position = {e.x / kCmPerM, e.y / kCmPerM};
    f.yaw_rad = e.yaw / kYawUnitsPerRad;
    f.speed_mps = e.speed / kCmPerM;
    f.s_m = r.f32();
    f.d_m = r.f32();
    f.strict.tangential_mps2 = r.f32();
    f.strict.normal_mps2 = r.f32();
    f.strict.acceleration_mps2 = r.f32();
    f.strict.jerk_mps3 = r.f32();
    f.distance_m = r.f32();
    f.incident_free_m = r.f32();
    f.best_incident_free_m = r.f32();
    const std::size_t cars = r.u8();
    cars_after(kind, at, r, cars, p.size());
    f.cars.resize(cars);
    for (std::size_t k = 0; k < cars; ++k) {
      const FixedCar& c = next_[k];
      f.cars[k] = {c.id,
                   {c.at.x / kCmPerM, c.at.y / kCmPerM},
                   c.at.yaw / kYawUnitsPerRad,
                   c.at.speed / kCmPerM};
    }
    // Added within version 2: TTC ahead, TTC entering a lane, headway (older files: none).
    f.safety = {};
    if (r.remaining() >= kFrameSafetyBytes) {
      f.safety.ttc_ahead_s = seconds_of(r.u16());
      f.safety.ttc_entering_s = seconds_of(r.u16());
      f.safety.headway_s = seconds_of(r.u16());
    }
    ego_ = e;
    cars_.swap(next_);
    st_.last_step = f.step;
    sink_.frame(f);
  }

  void path_record(std::uint8_t kind, std::string_view p, std::size_t at, Reader& r) {
    if (!st_.last_step) bad_record(kind, at, "a path before the first frame");
    need(kind, at, p, 2);
    ReplayPath path;
    path.step = *st_.last_step;
    const std::size_t m = r.u16();
    path.points.resize(m);
    std::int64_t x = ego_.x;
    std::int64_t y = ego_.y;
    for (std::size_t i = 0; i < m; ++i) {
      const auto dx = r.delta();
      const auto dy = dx ? r.delta() : std::nullopt;
      if (!dy) {
        bad_varint(
            kind, at, r,
            "its " + std::to_string(m) + " points (from point " + std::to_string(i + 1) + ")",
            p.size());
      }
      x = in_range(kind, at, x + *dx, INT32_MIN, INT32_MAX, "a path point", "x");
      y = in_range(kind, at, y + *dy, INT32_MIN, INT32_MAX, "a path point", "y");
      path.points[i] = {static_cast<double>(x) / kCmPerM, static_cast<double>(y) / kCmPerM};
    }
    // Added later within version 2.
    if (r.remaining() >= kExactHeadBytes) read_exact(kind, at, p, r, path);
    sink_.path(std::move(path));
  }

  // The exact points of a path (after its rounded ones): as deltas of units, or as the bits
  // of each double, each XOR the one before.
  void read_exact(std::uint8_t kind, std::size_t at, std::string_view p, Reader& r,
                  ReplayPath& path) const {
    const std::uint32_t n = r.u32();
    const std::uint8_t form = r.u8();
    if (n != path.points.size() || form > 1) {
      bad_record(kind, at,
                 "its exact points are " + std::to_string(n) + " of form " + std::to_string(form) +
                     ", its points " + std::to_string(path.points.size()));
    }
    path.exact.resize(n);
    if (form == 1) {
      std::int64_t ux = 0;
      std::int64_t uy = 0;
      for (std::size_t i = 0; i < n; ++i) {
        const auto dx = r.delta();
        const auto dy = dx ? r.delta() : std::nullopt;
        if (!dy) {
          bad_varint(kind, at, r, "its exact points (from point " + std::to_string(i + 1) + ")",
                     p.size());
        }
        ux += *dx;
        uy += *dy;
        path.exact[i] = {exact_of_units(ux), exact_of_units(uy)};
      }
    } else {
      need(kind, at, p, p.size() - r.remaining() + std::size_t{n} * kExactPointBytes);
      std::uint64_t bx = 0;
      std::uint64_t by = 0;
      for (core::Vec2& e : path.exact) {
        bx ^= r.u64();
        by ^= r.u64();
        e = {std::bit_cast<double>(bx), std::bit_cast<double>(by)};
      }
    }
    for (const core::Vec2& e : path.exact) {
      if (!std::isfinite(e.x) || !std::isfinite(e.y)) {
        bad_record(kind, at, "an exact path point that is not finite");
      }
    }
    path.has_exact = true;
  }

  void incident_record(std::uint8_t kind, std::string_view p, std::size_t at, Reader& r) {
    if (!st_.last_step) bad_record(kind, at, "an incident before the first frame");
    need(kind, at, p, kIncidentBytes);
    ReplayIncident i;
    i.step = *st_.last_step;
    i.type = r.u8();
    if (static_cast<std::size_t>(i.type) >= incident_types_) {
      bad_record(kind, at,
                 "incident type " + std::to_string(i.type) + " is not in the header's " +
                     std::to_string(incident_types_) + " incident_types");
    }
    i.value = r.f32();
    i.s_m = r.f32();
    i.lane = r.u8();
    i.position.x = r.metres();
    i.position.y = r.metres();
    if (r.remaining() >= kCollisionClassBytes) {  // added within version 2
      const std::uint8_t k = r.u8();
      const std::uint8_t fault = r.u8();
      if (k != kNoCollisionKind) {
        if (k >= collision_kinds_ || fault > 1) {
          bad_record(kind, at,
                     "collision kind " + std::to_string(k) + " (at fault " + std::to_string(fault) +
                         ") is not one of the header's " + std::to_string(collision_kinds_) +
                         " collision_kinds");
        }
        i.collision = sim::CollisionClass{static_cast<sim::CollisionKind>(k), fault == 1};
      }
    }
    if (r.remaining() >= kContactBytes) {  // added later within version 2
      const std::uint32_t contact = r.u32();
      if (contact > 0 && (!i.collision || i.type != collision_type_)) {
        bad_record(kind, at, "a contact number on an incident that is no classified collision");
      }
      if (contact > 0) i.contact = static_cast<long>(contact) - 1;
    }
    sink_.incident(i);
  }

  void checkpoint_record(std::uint8_t kind, std::string_view p, std::size_t at) {
    if (!st_.last_step) bad_record(kind, at, "a checkpoint before the first frame");
    ReplayCheckpoint c;
    c.step = *st_.last_step;
    try {
      const sim::Checkpoint decoded = sim::decode_checkpoint(p, "the checkpoint");
      if (decoded.info.step != c.step) {
        bad_record(kind, at,
                   "a checkpoint of step " + std::to_string(decoded.info.step) + " at frame " +
                       std::to_string(c.step));
      }
      c.t_s = decoded.info.t_s;
    } catch (const core::StateError& e) {
      bad_record(kind, at, e.what());
    }
    c.bytes.assign(p);
    sink_.checkpoint(std::move(c));
  }

  void end_record(std::uint8_t kind, std::string_view p, std::size_t at) {
    std::string text(p);
    if (!json::accept(text)) bad_record(kind, at, "the report is not valid JSON");
    ended_ = true;
    sink_.end(std::move(text));
  }

  std::string_view bytes_;
  std::string_view name_;
  Sink& sink_;
  DecodeState& st_;
  std::size_t body_start_ = 0;
  std::size_t inflated_base_ = 0;  // inflated offset of buf[0]
  std::size_t incident_types_ = 0;
  int collision_type_ = -1;  ///< the index of "collision" among the header's incident types
  std::size_t collision_kinds_ = 0;
  bool ended_ = false;
  ReplayFrame frame_;           // reused
  Fixed ego_;                   // the last frame's ego, as stored (zero before the first)
  std::vector<FixedCar> cars_;  // the last frame's cars, as stored
  std::vector<FixedCar> next_;  // the frame being read
  std::vector<Fixed> base_;     // what each car of next_ is coded against
  std::vector<bool> in_frame_;  // ids seen in next_ (65536 flags)
};

struct BuildSink final : Sink {
  Replay out;
  void header(ReplayHeader h, std::string text) override {
    out.header = std::move(h);
    out.header_json = std::move(text);
  }
  void frame(const ReplayFrame& f) override { out.frames.push_back(f); }
  void path(ReplayPath&& p) override { out.paths.push_back(std::move(p)); }
  void incident(const ReplayIncident& i) override { out.incidents.push_back(i); }
  void end(std::string text) override { out.end_json = std::move(text); }
  void unknown() override { ++out.unknown_records; }
  void checkpoint(ReplayCheckpoint&& c) override { out.checkpoints.push_back(std::move(c)); }
};

struct CountSink final : Sink {
  ReplayCheck* check = nullptr;
  void header(ReplayHeader, std::string) override {}
  void frame(const ReplayFrame&) override { ++check->frames; }
  void path(ReplayPath&&) override {}
  void incident(const ReplayIncident&) override { ++check->incidents; }
  void end(std::string) override {}
  void unknown() override {}
  void checkpoint(ReplayCheckpoint&&) override { ++check->checkpoints; }
};

}  // namespace

Replay parse_replay(std::string_view bytes, std::string_view name) {
  BuildSink sink;
  DecodeState state;
  Decoder(bytes, name, sink, state).run();
  return std::move(sink.out);
}

Replay read_replay(const std::filesystem::path& path) {
  // Opened without waiting (a FIFO would wait for a writer) and read only if it is a regular
  // file of at most kMaxReplayBytes: /dev/zero would be read until memory ran out.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw ReplayError(path.string() + ": cannot open (" + std::strerror(errno) + ")");
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    throw ReplayError(path.string() + ": not a regular file");
  }
  const auto too_big = [&] {
    return ReplayError(path.string() + ": larger than the " +
                       std::to_string(kMaxReplayBytes >> 30) + " GiB a replay may be");
  };
  if (static_cast<std::uintmax_t>(st.st_size) > kMaxReplayBytes) throw too_big();
  std::string bytes;
  bytes.reserve(static_cast<std::size_t>(st.st_size));
  char chunk[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      throw ReplayError(path.string() + ": read error (" + std::strerror(errno) + ")");
    }
    bytes.append(chunk, static_cast<std::size_t>(n));
    if (bytes.size() > kMaxReplayBytes) throw too_big();
  }
  return parse_replay(bytes, path.string());
}

ReplayCheck check_replay(std::string_view bytes, std::string_view name) {
  ReplayCheck check;
  CountSink sink;
  sink.check = &check;
  DecodeState state;
  try {
    Decoder(bytes, name, sink, state).run();
  } catch (const ReplayError& e) {
    check.error = e.what();
  }
  check.records = state.records;
  if (state.last_step) check.duration_s = static_cast<double>(*state.last_step) * state.step_s;
  return check;
}

}  // namespace overtake::replay
