#include "overtake/core/track.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/random.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/core/units.hpp"

namespace overtake::core {
namespace {

// ---- Limits and tuning (metres unless named otherwise) ----

constexpr double kMinLoopLengthM = 1000.0;
constexpr double kMaxLoopLengthM = 200000.0;
constexpr double kMinLengthPerMinRadius = 24.0;   // room for four corners and a right bend
constexpr double kMinSpacingRatio = 1.2;          // max_spacing_m / min_spacing_m, to generate
constexpr double kMaxMinSpacingPerRadius = 0.25;  // min_spacing_m / min_radius_m, to generate
constexpr double kLengthTolerance = 0.02;         // fraction of length_m
constexpr double kSmallLoopLengthM = 7500.0;      // loops up to this fit the default box
constexpr double kSmallLoopMaxCoordinateM = 1000.0;
constexpr double kMaxStartStraightFraction = 0.1;  // of the loop
constexpr double kMaxNormalErrorDeg = 5.0;
constexpr double kMaxSErrorM = 0.05;
constexpr double kCurvatureStepM = 1.0;  // curvature samples of the check
constexpr double kPairStepM = 2.0;       // samples for clearance and crossings
constexpr std::size_t kMaxPairSamples = 6000;
// Two samples of a road with every radius above the chord's length apart along it are at
// least 2/pi of that apart in a straight line; closer than this fraction of it means a
// different stretch of road.
constexpr double kDistinctChordFraction = 0.9 * 2.0 / kPi;

constexpr int kMaxAttempts = 64;
constexpr std::uint64_t kShapeStream = 0;
constexpr double kReferenceLengthM = 7000.0;  // the shape's lengths scale with length_m / this
constexpr double kRadiusMargin = 1.2;         // bends are drawn this much wider than the limit
constexpr double kMaxCornerRadiusPerLength = 1.0 / 20.0;
constexpr double kMinFreeFraction = 0.04;      // of the loop: straight length left to square it
constexpr double kBehindStartM = 80.0;         // straight before the first waypoint
constexpr double kAfterStartStraightM = 60.0;  // straight beyond start_straight_m
constexpr double kIntegrationStepM = 4.0;
constexpr double kMinRampM = 60.0;  // shortest clothoid into or out of a bend
constexpr double kMinRampPerRadius = 0.35;
constexpr int kAspectSteps = 100;
constexpr int kSqueezeLevels = 4;       // steps from the drawn shape to the tightest
constexpr double kDentDeepening = 2.0;  // dent straights grow up to 1 + this times
constexpr double kBoxMarginM = 1.0;

// Waypoint spacing: the spec's straight spacing on straights, closer in bends (spacing divided by
// 1 + kBendSpacingFactor * min_radius_m * |curvature|), the curvature taken as the largest
// within kSpacingWindowM, nor over kMaxSpacingPerRadius times the radius; each waypoint then
// moves by up to kSpacingJitter of a step.
constexpr double kBendSpacingFactor = 0.9;
constexpr double kSpacingWindowM = 25.0;
constexpr double kSpacingJitter = 0.08;
constexpr double kMaxSpacingPerRadius = 0.15;  // and never more than this times the radius
constexpr double kSpacingMargin = 1.2;         // targets stay this far inside the spec's limits
constexpr double kPlacementStepM = 1.0;

// ---- Messages ----

std::string num(double v, int decimals = 1) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

[[noreturn]] void bad_field(const std::string& field, const std::string& why) {
  throw std::invalid_argument("TrackSpec." + field + ": " + why);
}

void require_finite(double v, const char* field) {
  if (!std::isfinite(v)) bad_field(field, "must be finite (got " + std::to_string(v) + ")");
}

// What checking needs of a spec.
void validate_check_spec(const TrackSpec& spec) {
  require_finite(spec.length_m, "length_m");
  require_finite(spec.min_radius_m, "min_radius_m");
  require_finite(spec.min_spacing_m, "min_spacing_m");
  require_finite(spec.max_spacing_m, "max_spacing_m");
  require_finite(spec.min_clearance_m, "min_clearance_m");
  require_finite(spec.shoulder_m, "shoulder_m");
  require_finite(spec.max_abs_coordinate_m, "max_abs_coordinate_m");
  require_finite(spec.start_straight_m, "start_straight_m");
  require_finite(spec.straight_spacing_m, "straight_spacing_m");
  require_finite(spec.bend_radius_m, "bend_radius_m");
  require_finite(spec.road.lane_width_m, "road.lane_width_m");
  if (!(spec.length_m > 0.0)) bad_field("length_m", "must be positive");
  if (!(spec.min_radius_m > 0.0)) bad_field("min_radius_m", "must be positive");
  if (!(spec.min_spacing_m > 0.0)) bad_field("min_spacing_m", "must be positive");
  if (!(spec.min_spacing_m < spec.max_spacing_m)) {
    bad_field("min_spacing_m", "must be below max_spacing_m (" + num(spec.min_spacing_m) +
                                   " >= " + num(spec.max_spacing_m) + ")");
  }
  if (spec.min_clearance_m < 0.0) bad_field("min_clearance_m", "must not be negative");
  if (spec.shoulder_m < 0.0) bad_field("shoulder_m", "must not be negative");
  if (spec.max_abs_coordinate_m < 0.0) {
    bad_field("max_abs_coordinate_m", "must not be negative (0 picks the default)");
  }
  if (spec.start_straight_m < 0.0) bad_field("start_straight_m", "must not be negative");
  if (!(spec.straight_spacing_m > 0.0)) bad_field("straight_spacing_m", "must be positive");
  if (!(spec.bend_radius_m > 0.0)) bad_field("bend_radius_m", "must be positive");
  if (spec.road.lane_count < 1) bad_field("road.lane_count", "must be at least 1");
  if (!(spec.road.lane_width_m > 0.0)) bad_field("road.lane_width_m", "must be positive");
}

double road_width_m(const TrackSpec& spec) {
  return spec.road.lane_count * spec.road.lane_width_m;
}

double required_start_straight_m(const TrackSpec& spec) {
  return std::min(spec.start_straight_m, kMaxStartStraightFraction * spec.length_m);
}

// ---- The shape: a curvature profile ----

// A stretch of road whose curvature changes linearly along it: a straight, an arc or a
// clothoid.
struct Piece {
  double length_m = 0.0;
  double k0_1pm = 0.0;  // curvature at the start, positive to the left
  double k1_1pm = 0.0;  // at the end
};

struct Pose {
  Vec2 position;
  double heading_rad = 0.0;
};

double heading_change(const Piece& p, double u) {
  return p.k0_1pm * u + 0.5 * (p.k1_1pm - p.k0_1pm) * u * u / p.length_m;
}

// Pose at `u1` metres into the piece, from the pose `at` at `u0` metres: exact heading,
// position by composite three-point Gauss-Legendre quadrature.
Pose advance(const Piece& p, const Pose& at, double u0, double u1) {
  const double span = u1 - u0;
  if (span <= 0.0) return at;
  if (p.k0_1pm == 0.0 && p.k1_1pm == 0.0) {
    return {at.position + span * Vec2{std::cos(at.heading_rad), std::sin(at.heading_rad)},
            at.heading_rad};
  }
  static constexpr double kNode = 0.3872983346207417;  // sqrt(3/5) / 2: nodes at mid +- kNode h
  static constexpr double kWeightSide = 5.0 / 18.0;
  static constexpr double kWeightMid = 8.0 / 18.0;
  const double base = at.heading_rad - heading_change(p, u0);
  const int n = std::max(1, static_cast<int>(std::ceil(span / kIntegrationStepM)));
  const double h = span / n;
  const double offsets[3] = {-kNode * h, 0.0, kNode * h};
  const double weights[3] = {kWeightSide * h, kWeightMid * h, kWeightSide * h};
  Vec2 sum;
  for (int i = 0; i < n; ++i) {
    const double mid = u0 + (i + 0.5) * h;
    for (int q = 0; q < 3; ++q) {
      const double a = base + heading_change(p, mid + offsets[q]);
      sum = sum + weights[q] * Vec2{std::cos(a), std::sin(a)};
    }
  }
  return {at.position + sum, base + heading_change(p, u1)};
}

// The closed course: pieces laid end to end from the origin, heading along +x.
class Course {
 public:
  explicit Course(std::vector<Piece> pieces) : pieces_(std::move(pieces)) {
    starts_.reserve(pieces_.size() + 1);
    poses_.reserve(pieces_.size() + 1);
    double s = 0.0;
    Pose pose;
    for (const Piece& p : pieces_) {
      starts_.push_back(s);
      poses_.push_back(pose);
      pose = advance(p, pose, 0.0, p.length_m);
      s += p.length_m;
    }
    starts_.push_back(s);
    poses_.push_back(pose);
  }

  [[nodiscard]] double length_m() const { return starts_.back(); }
  [[nodiscard]] const Pose& end() const { return poses_.back(); }

  [[nodiscard]] Pose pose_at(double s) const {
    const std::size_t i = piece_at(s);
    return advance(pieces_[i], poses_[i], 0.0, s - starts_[i]);
  }

  [[nodiscard]] double curvature_at(double s) const {
    const std::size_t i = piece_at(s);
    const Piece& p = pieces_[i];
    const double u = std::clamp((s - starts_[i]) / p.length_m, 0.0, 1.0);
    return p.k0_1pm + (p.k1_1pm - p.k0_1pm) * u;
  }

  // Smallest box around the divider line: {min corner, max corner}.
  [[nodiscard]] std::pair<Vec2, Vec2> bounds() const {
    Vec2 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    Vec2 hi = -1.0 * lo;
    constexpr double kStepM = 5.0;
    for (std::size_t i = 0; i < pieces_.size(); ++i) {
      const Piece& p = pieces_[i];
      const int n = std::max(1, static_cast<int>(std::ceil(p.length_m / kStepM)));
      Pose pose = poses_[i];
      for (int k = 0; k <= n; ++k) {
        if (k > 0) pose = advance(p, pose, p.length_m * (k - 1) / n, p.length_m * k / n);
        lo = {std::min(lo.x, pose.position.x), std::min(lo.y, pose.position.y)};
        hi = {std::max(hi.x, pose.position.x), std::max(hi.y, pose.position.y)};
      }
    }
    return {lo, hi};
  }

 private:
  [[nodiscard]] std::size_t piece_at(double s) const {
    const auto it = std::upper_bound(starts_.begin(), starts_.end() - 1, s);
    const auto i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - starts_.begin() - 1));
    return std::min(i, pieces_.size() - 1);
  }

  std::vector<Piece> pieces_;
  std::vector<double> starts_;  // s of each piece's start, then the total
  std::vector<Pose> poses_;     // pose at each piece's start, then at the end
};

// A piece of the draft: either fixed, or a straight along side `side` (0: +x, 1: +y, 2: -x,
// 3: -y) that takes a share, in proportion to `weight`, of the length that side has to add
// for the loop to close.
struct Slot {
  Piece piece;
  int side = -1;
  double weight = 0.0;
};

using Stretch = std::vector<Piece>;

void add_straight(Stretch& out, double length_m) {
  if (length_m > 0.0) out.push_back({length_m, 0.0, 0.0});
}

// A bend turning `turn_rad` (positive left) at `radius_m`, entered and left through clothoids
// that take `ramp_fraction` of the turn's arc length each, and at least kMinRampM (less in
// bends tighter than kMinRampM / kMinRampPerRadius). A bend too short for its ramps is two
// clothoids only, at a wider peak radius.
void add_bend(Stretch& out, double turn_rad, double radius_m, double ramp_fraction) {
  const double arc = std::abs(turn_rad) * radius_m;
  const double ramp =
      std::max(ramp_fraction * arc, std::min(kMinRampM, kMinRampPerRadius * radius_m));
  const double hold = std::max(0.0, arc - ramp);
  const double k = turn_rad / (ramp + hold);
  out.push_back({ramp, 0.0, k});
  if (hold > 0.0) out.push_back({hold, k, k});
  out.push_back({ramp, k, 0.0});
}

double stretch_length(const Stretch& s) {
  double total = 0.0;
  for (const Piece& p : s) total += p.length_m;
  return total;
}

// Radii and lengths the shape draws from, for one spec.
struct ShapeRanges {
  double scale = 1.0;       // length_m / kReferenceLengthM
  double left_lo_m = 0.0;   // smallest divider radius of a left bend
  double right_lo_m = 0.0;  // ... of a right bend (the outer edge is then its inner side)
  double corner_hi_m = 0.0;
  double shoulder_hi_m = 0.0;
  double apex_hi_m = 0.0;
  double gentle_lo_m = 0.0;  // jogs
  double gentle_hi_m = 0.0;
};

ShapeRanges ranges_for(const TrackSpec& spec) {
  ShapeRanges r;
  const double rmin = spec.min_radius_m;
  r.scale = spec.length_m / kReferenceLengthM;
  r.left_lo_m = kRadiusMargin * rmin;
  r.right_lo_m = kRadiusMargin * rmin + road_width_m(spec);
  r.corner_hi_m =
      std::max(1.25 * r.left_lo_m, std::min(kMaxCornerRadiusPerLength * spec.length_m, 2.5 * rmin));
  r.shoulder_hi_m = std::max(1.25 * r.left_lo_m, 3.0 * rmin);
  r.apex_hi_m = std::max(1.25 * r.right_lo_m, 3.0 * rmin);
  r.gentle_lo_m = std::max(r.right_lo_m, 3.0 * rmin);
  r.gentle_hi_m = std::max(r.gentle_lo_m, 8.0 * rmin);
  return r;
}

// One bend: turns `turn_rad` (positive left) at `radius_m`, with clothoids taking
// `ramp_fraction` of the turn's arc length at each end.
struct Bend {
  double turn_rad = 0.0;
  double radius_m = 0.0;
  double ramp_fraction = 0.0;
};

enum class FeatureKind { kCorner, kDent, kJog };

// A corner (+90 degrees), an inward dent (left, right, left: no net turn) or a jog (a gentle
// bend and its opposite): bends with straights between them.
struct Feature {
  FeatureKind kind = FeatureKind::kCorner;
  std::vector<Bend> bends;
  std::vector<double> straights_m;  // one fewer than bends
  int random_side = -1;             // the side drawn for it, or -1: the best-balancing side
  double key = 0.0;                 // order along its side
};

// The pieces of a feature. `squeeze` in [0, 1] tightens corners towards `tight_radius_m` and
// deepens dents: both fit more road into the same box.
Stretch build_feature(const Feature& f, double squeeze, double tight_radius_m) {
  Stretch out;
  for (std::size_t i = 0; i < f.bends.size(); ++i) {
    Bend b = f.bends[i];
    if (f.kind == FeatureKind::kCorner) b.radius_m -= squeeze * (b.radius_m - tight_radius_m);
    add_bend(out, b.turn_rad, b.radius_m, b.ramp_fraction);
    if (i < f.straights_m.size()) {
      const double deepen = f.kind == FeatureKind::kDent ? 1.0 + kDentDeepening * squeeze : 1.0;
      add_straight(out, f.straights_m[i] * deepen);
    }
  }
  return out;
}

double ramp_fraction(Rng& rng) {
  return rng.uniform(0.2, 0.5);
}

Feature draw_corner(Rng& rng, const ShapeRanges& r) {
  Feature f;
  f.kind = FeatureKind::kCorner;
  const double quarter = 0.5 * kPi;
  if (rng.chance(0.3)) {  // split in two bends with a short straight between
    const double w = rng.uniform(0.3, 0.7);
    f.bends.push_back({w * quarter, rng.uniform(r.left_lo_m, r.corner_hi_m), ramp_fraction(rng)});
    f.straights_m.push_back(rng.uniform(20.0, 150.0) * r.scale);
    f.bends.push_back(
        {(1.0 - w) * quarter, rng.uniform(r.left_lo_m, r.corner_hi_m), ramp_fraction(rng)});
  } else {
    f.bends.push_back({quarter, rng.uniform(r.left_lo_m, r.corner_hi_m), ramp_fraction(rng)});
  }
  return f;
}

Feature draw_dent(Rng& rng, const ShapeRanges& r) {
  Feature f;
  f.kind = FeatureKind::kDent;
  const double phi = deg_to_rad(rng.uniform(15.0, 40.0));
  f.bends.push_back({phi, rng.uniform(r.left_lo_m, r.shoulder_hi_m), ramp_fraction(rng)});
  f.straights_m.push_back(rng.uniform(0.0, 200.0) * r.scale);
  f.bends.push_back({-2.0 * phi, rng.uniform(r.right_lo_m, r.apex_hi_m), ramp_fraction(rng)});
  f.straights_m.push_back(rng.uniform(0.0, 200.0) * r.scale);
  f.bends.push_back({phi, rng.uniform(r.left_lo_m, r.shoulder_hi_m), ramp_fraction(rng)});
  return f;
}

Feature draw_jog(Rng& rng, const ShapeRanges& r) {
  Feature f;
  f.kind = FeatureKind::kJog;
  const double psi = deg_to_rad(rng.uniform(8.0, 25.0)) * (rng.chance(0.5) ? 1.0 : -1.0);
  f.bends.push_back({psi, rng.uniform(r.gentle_lo_m, r.gentle_hi_m), ramp_fraction(rng)});
  f.straights_m.push_back(rng.uniform(0.0, 150.0) * r.scale);
  f.bends.push_back({-psi, rng.uniform(r.gentle_lo_m, r.gentle_hi_m), ramp_fraction(rng)});
  return f;
}

// Everything one attempt draws: four corners, the dents and jogs on the sides, and the
// weights that share each side's straight length among its gaps.
struct Shape {
  std::array<Feature, 4> corners;
  std::vector<Feature> features;   // dents first, then jogs
  std::vector<double> side_noise;  // four per feature
  std::vector<double> gap_weight;
};

Shape draw_shape(Rng& rng, const TrackSpec& spec) {
  const ShapeRanges r = ranges_for(spec);
  Shape shape;
  for (auto& c : shape.corners) c = draw_corner(rng, r);
  const int dents_lo = spec.length_m >= 4000.0 ? 2 : 1;
  const int dents_hi = std::max(dents_lo, static_cast<int>(std::lround(spec.length_m / 1750.0)));
  const int dents = rng.uniform_int(dents_lo, dents_hi);
  const int jogs = rng.uniform_int(0, 3);
  for (int i = 0; i < dents + jogs; ++i) {
    Feature f = i < dents ? draw_dent(rng, r) : draw_jog(rng, r);
    // Half of them on a random side, the others where they best balance the loop.
    f.random_side = rng.chance(0.5) ? rng.uniform_int(0, 3) : -1;
    f.key = rng.uniform01();
    shape.features.push_back(std::move(f));
  }
  shape.side_noise.resize(shape.features.size() * 4);
  for (double& v : shape.side_noise) v = rng.uniform(0.0, 0.05 * spec.length_m);
  shape.gap_weight.resize(shape.features.size() + 4);
  for (double& v : shape.gap_weight) v = rng.uniform(0.5, 1.5);
  return shape;
}

// The draft of one layout: fixed pieces, and side straights whose lengths are settled later
// so that the loop closes.
struct Draft {
  std::vector<Slot> slots;
  double fixed_length_m = 0.0;  // everything but the side straights' extra length
};

// `v` turned by `quarters` times 90 degrees counter-clockwise.
Vec2 turn_quarters(Vec2 v, int quarters) {
  switch (((quarters % 4) + 4) % 4) {
    case 1:
      return {-v.y, v.x};
    case 2:
      return {-v.x, -v.y};
    case 3:
      return {v.y, -v.x};
    default:
      return v;
  }
}

// How far a stretch moves the road, starting along +x.
Vec2 displacement_of(const Stretch& s) {
  return Course(s).end().position;
}

// Lays the shape out: corners and the start in place, then each feature on its side. Drops
// the last-drawn features (jogs first) while the side straights cannot close the loop.
std::optional<Draft> lay_out(const Shape& shape, const TrackSpec& spec, double squeeze) {
  const ShapeRanges r = ranges_for(spec);
  std::array<Stretch, 4> corners;
  for (std::size_t k = 0; k < 4; ++k) {
    corners[k] = build_feature(shape.corners[k], squeeze, r.left_lo_m);
  }
  struct Placed {
    Stretch pieces;
    Vec2 shift;  // displacement when laid along +x
    int side = 0;
    double key = 0.0;
  };
  std::vector<Placed> placed;
  for (const Feature& f : shape.features) {
    Placed p;
    p.pieces = build_feature(f, squeeze, r.left_lo_m);
    p.shift = displacement_of(p.pieces);
    p.key = f.key;
    placed.push_back(std::move(p));
  }

  const double start_gap =
      required_start_straight_m(spec) + kAfterStartStraightM * std::min(1.0, r.scale);
  const double behind_start = kBehindStartM * std::min(1.0, r.scale);
  const double gap_min = 30.0 * r.scale;
  while (true) {
    Vec2 open = {start_gap + behind_start, 0.0};
    double fixed = start_gap + behind_start;
    for (int k = 0; k < 4; ++k) {
      const double gap = k > 0 ? gap_min : 0.0;
      open = open + turn_quarters(displacement_of(corners[static_cast<std::size_t>(k)]), k) +
             turn_quarters({gap, 0.0}, k);
      fixed += stretch_length(corners[static_cast<std::size_t>(k)]) + gap;
    }
    for (std::size_t i = 0; i < placed.size(); ++i) {
      Placed& p = placed[i];
      const Vec2 step = p.shift + Vec2{gap_min, 0.0};
      if (shape.features[i].random_side >= 0) {
        p.side = shape.features[i].random_side;
      } else {
        double best = std::numeric_limits<double>::infinity();
        for (int k = 0; k < 4; ++k) {
          const Vec2 o = open + turn_quarters(step, k);
          const double cost =
              std::abs(o.x) + std::abs(o.y) + shape.side_noise[4 * i + static_cast<std::size_t>(k)];
          if (cost < best) {
            best = cost;
            p.side = k;
          }
        }
      }
      open = open + turn_quarters(step, p.side);
      fixed += stretch_length(p.pieces) + gap_min;
    }
    const double free = spec.length_m - fixed - std::abs(open.x) - std::abs(open.y);
    if (free > kMinFreeFraction * spec.length_m) break;
    if (placed.size() <= 1) return std::nullopt;
    placed.pop_back();
  }

  std::stable_sort(placed.begin(), placed.end(), [](const Placed& a, const Placed& b) {
    return a.side != b.side ? a.side < b.side : a.key < b.key;
  });

  Draft d;
  std::size_t gap_index = 0;
  auto push_gap = [&](int side, double base) {
    d.slots.push_back({{base, 0.0, 0.0}, side, shape.gap_weight[gap_index++]});
  };
  auto push_fixed = [&](const Stretch& s) {
    for (const Piece& p : s) d.slots.push_back({p, -1, 0.0});
  };
  std::size_t next = 0;
  for (int side = 0; side < 4; ++side) {
    push_gap(side, side == 0 ? start_gap : gap_min);
    for (; next < placed.size() && placed[next].side == side; ++next) {
      push_fixed(placed[next].pieces);
      push_gap(side, gap_min);
    }
    push_fixed(corners[static_cast<std::size_t>(side)]);
  }
  d.slots.push_back({{behind_start, 0.0, 0.0}, -1, 0.0});
  for (const Slot& s : d.slots) d.fixed_length_m += s.piece.length_m;
  return d;
}

// Each side straight's share of its side's extra length.
std::vector<double> gap_shares(const Draft& d) {
  std::array<double, 4> weight_sum{};
  for (const Slot& s : d.slots) {
    if (s.side >= 0) weight_sum[static_cast<std::size_t>(s.side)] += s.weight;
  }
  std::vector<double> share(d.slots.size(), 0.0);
  for (std::size_t i = 0; i < d.slots.size(); ++i) {
    const Slot& s = d.slots[i];
    if (s.side >= 0) share[i] = s.weight / weight_sum[static_cast<std::size_t>(s.side)];
  }
  return share;
}

// The course with each side's straights lengthened by `extra[side]`.
Course build_course(const Draft& d, const std::array<double, 4>& extra) {
  const std::vector<double> share = gap_shares(d);
  std::vector<Piece> pieces;
  pieces.reserve(d.slots.size());
  for (std::size_t i = 0; i < d.slots.size(); ++i) {
    Piece p = d.slots[i].piece;
    if (d.slots[i].side >= 0)
      p.length_m += extra[static_cast<std::size_t>(d.slots[i].side)] * share[i];
    pieces.push_back(p);
  }
  return Course(std::move(pieces));
}

struct Closed {
  Course course;
  Vec2 offset;  // added to every position to centre the outline on the origin
  double half_extent_m = 0.0;
};

// Closes the draft at arc length `arc_length_m`, as square as it goes; nullopt when it cannot
// close or does not fit the box. Lengthening the side straights only moves the pieces after
// them, so the outline for each split is found from one course's samples.
std::optional<Closed> close_course(const Draft& d, double arc_length_m, const TrackSpec& spec) {
  const Course base = build_course(d, {0.0, 0.0, 0.0, 0.0});
  const Vec2 gap = base.end().position;  // what the side straights must make up
  const double extra = arc_length_m - d.fixed_length_m;
  const double free = extra - std::abs(gap.x) - std::abs(gap.y);
  if (!(free > 0.0)) return std::nullopt;

  // Samples of the base course, by slot.
  constexpr double kStepM = 5.0;
  std::vector<std::vector<Vec2>> samples(d.slots.size());
  {
    double s = 0.0;
    for (std::size_t i = 0; i < d.slots.size(); ++i) {
      const double len = d.slots[i].piece.length_m;
      const int n =
          d.slots[i].side >= 0 ? 1 : std::max(1, static_cast<int>(std::ceil(len / kStepM)));
      for (int k = 0; k <= n; ++k) samples[i].push_back(base.pose_at(s + len * k / n).position);
      s += len;
    }
  }
  const std::vector<double> share = gap_shares(d);
  auto split = [&](double lambda) {
    const double sx = std::abs(gap.x) + free * lambda;
    const double sy = extra - sx;
    return std::array<double, 4>{0.5 * (sx - gap.x), 0.5 * (sy - gap.y), 0.5 * (sx + gap.x),
                                 0.5 * (sy + gap.y)};
  };
  auto outline = [&](const std::array<double, 4>& e) {
    Vec2 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    Vec2 hi = -1.0 * lo;
    Vec2 shift;
    for (std::size_t i = 0; i < d.slots.size(); ++i) {
      const Vec2 before = shift;
      const int side = d.slots[i].side;
      if (side >= 0) {
        shift = shift + turn_quarters({e[static_cast<std::size_t>(side)] * share[i], 0.0}, side);
      }
      for (std::size_t k = 0; k < samples[i].size(); ++k) {
        const Vec2 q = samples[i][k] + (k + 1 == samples[i].size() ? shift : before);
        lo = {std::min(lo.x, q.x), std::min(lo.y, q.y)};
        hi = {std::max(hi.x, q.x), std::max(hi.y, q.y)};
      }
    }
    return std::pair{lo, hi};
  };
  double best_lambda = 0.0;
  double best_half = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= kAspectSteps; ++i) {
    const double lambda = static_cast<double>(i) / kAspectSteps;
    const auto [lo, hi] = outline(split(lambda));
    const double half = 0.5 * std::max(hi.x - lo.x, hi.y - lo.y);
    if (half < best_half) {
      best_half = half;
      best_lambda = lambda;
    }
  }
  const double limit =
      max_abs_coordinate_for(spec) - road_width_m(spec) - spec.shoulder_m - kBoxMarginM;
  if (best_half > limit) return std::nullopt;
  Course course = build_course(d, split(best_lambda));
  const auto [lo, hi] = course.bounds();
  const double half = 0.5 * std::max(hi.x - lo.x, hi.y - lo.y);
  if (half > limit) return std::nullopt;
  return Closed{std::move(course), -0.5 * (lo + hi), half};
}

// Spacing of waypoints along the course.
struct SpacingPlan {
  double straight_m = 0.0;
  double lo_m = 0.0;
  double hi_m = 0.0;
  double jitter = 0.0;  // fraction of a step each waypoint may move
  double bend_factor_m = 0.0;
};

SpacingPlan spacing_plan(const TrackSpec& spec) {
  SpacingPlan p;
  p.lo_m = kSpacingMargin * spec.min_spacing_m;
  p.hi_m = spec.max_spacing_m / kSpacingMargin;
  if (p.lo_m > p.hi_m) p.lo_m = p.hi_m = std::sqrt(spec.min_spacing_m * spec.max_spacing_m);
  p.straight_m = std::clamp(spec.straight_spacing_m, p.lo_m, p.hi_m);
  p.jitter = std::min({kSpacingJitter, 0.45 * (1.0 - spec.min_spacing_m / p.lo_m),
                       0.45 * (spec.max_spacing_m / p.hi_m - 1.0)});
  p.bend_factor_m = kBendSpacingFactor * spec.min_radius_m;
  return p;
}

double round_to(double v, double scale) {
  const double r = std::round(v * scale) / scale;
  return r == 0.0 ? 0.0 : r;  // no "-0.0000" in the file
}

// Waypoints along a closed course, rounded as the file prints them; s is the summed
// straight-line distance.
std::vector<Waypoint> place_waypoints(const Closed& closed, const SpacingPlan& plan,
                                      std::uint64_t jitter_seed) {
  const Course& c = closed.course;
  const double total = c.length_m();
  const auto grid = static_cast<std::size_t>(std::ceil(total / kPlacementStepM));
  const double step = total / static_cast<double>(grid);
  std::vector<double> abs_k(grid + 1);
  for (std::size_t i = 0; i <= grid; ++i) {
    abs_k[i] = std::abs(c.curvature_at(std::min(total, step * static_cast<double>(i))));
  }
  const auto window = static_cast<std::ptrdiff_t>(std::ceil(kSpacingWindowM / step));
  std::vector<double> density(grid + 1);
  for (std::size_t i = 0; i <= grid; ++i) {
    double k = 0.0;
    for (std::ptrdiff_t o = -window; o <= window; ++o) {
      // The course is a loop: wrap the window (grid and 0 are the same point).
      auto j = static_cast<std::ptrdiff_t>(i) + o;
      const auto g = static_cast<std::ptrdiff_t>(grid);
      j = ((j % g) + g) % g;
      k = std::max(k, abs_k[static_cast<std::size_t>(j)]);
    }
    const double wanted = std::min(plan.straight_m / (1.0 + plan.bend_factor_m * k),
                                   kMaxSpacingPerRadius / std::max(k, 1e-9));
    const double spacing = std::clamp(wanted, plan.lo_m, plan.hi_m);
    density[i] = 1.0 / spacing;
  }
  std::vector<double> cumulative(grid + 1, 0.0);
  for (std::size_t i = 1; i <= grid; ++i) {
    cumulative[i] = cumulative[i - 1] + 0.5 * step * (density[i - 1] + density[i]);
  }
  const double count_real = cumulative.back();
  const auto count = static_cast<std::size_t>(std::max(8.0, std::round(count_real)));
  const double per_index = count_real / static_cast<double>(count);

  Rng jitter(jitter_seed);
  std::vector<Waypoint> out;
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const double j = i == 0 ? 0.0 : plan.jitter * jitter.uniform(-1.0, 1.0);
    const double target = (static_cast<double>(i) + j) * per_index;
    const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), target);
    const auto k = static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(
        it - cumulative.begin() - 1, 0, static_cast<std::ptrdiff_t>(grid) - 1));
    const double frac = (target - cumulative[k]) / (cumulative[k + 1] - cumulative[k]);
    const double s = step * (static_cast<double>(k) + frac);
    const Pose pose = c.pose_at(s);
    Waypoint w;
    w.x_m = round_to(pose.position.x + closed.offset.x, 1e4);
    w.y_m = round_to(pose.position.y + closed.offset.y, 1e4);
    w.dx = round_to(std::sin(pose.heading_rad), 1e7);  // right of the direction of travel
    w.dy = round_to(-std::cos(pose.heading_rad), 1e7);
    out.push_back(w);
  }
  double s = 0.0;
  for (std::size_t i = 1; i < out.size(); ++i) {
    s += std::hypot(out[i].x_m - out[i - 1].x_m, out[i].y_m - out[i - 1].y_m);
    out[i].s_m = round_to(s, 1e4);
  }
  return out;
}

double chord_loop_length(const std::vector<Waypoint>& w) {
  return w.back().s_m + std::hypot(w.front().x_m - w.back().x_m, w.front().y_m - w.back().y_m);
}

// One attempt: a shape drawn from `seed`, laid out, closed and placed, squeezed as much as
// it takes to fit the box; nullopt when it does not fit.
std::optional<std::vector<Waypoint>> attempt_track(const TrackSpec& spec, std::uint64_t seed) {
  Rng rng(seed);
  const Shape shape = draw_shape(rng, spec);
  const std::uint64_t jitter_seed = rng.next();
  const SpacingPlan plan = spacing_plan(spec);
  for (int level = 0; level <= kSqueezeLevels; ++level) {
    const auto draft = lay_out(shape, spec, static_cast<double>(level) / kSqueezeLevels);
    if (!draft) continue;
    // The waypoints cut corners a little; a second pass lengthens the course by the shortfall.
    double arc = spec.length_m;
    std::vector<Waypoint> w;
    for (int pass = 0; pass < 2; ++pass) {
      const auto closed = close_course(*draft, arc, spec);
      if (!closed) {
        w.clear();
        break;
      }
      w = place_waypoints(*closed, plan, jitter_seed);
      arc += spec.length_m - chord_loop_length(w);
    }
    if (!w.empty()) return w;
  }
  return std::nullopt;
}

// ---- Checking ----

bool segments_cross(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  const double o1 = cross(b - a, c - a);
  const double o2 = cross(b - a, d - a);
  const double o3 = cross(d - c, a - c);
  const double o4 = cross(d - c, b - c);
  if (o1 * o2 > 0.0 || o3 * o4 > 0.0) return false;
  // Collinear: overlap of the boxes decides.
  return std::max(std::min(a.x, b.x), std::min(c.x, d.x)) <=
             std::min(std::max(a.x, b.x), std::max(c.x, d.x)) &&
         std::max(std::min(a.y, b.y), std::min(c.y, d.y)) <=
             std::min(std::max(a.y, b.y), std::max(c.y, d.y));
}

void check_waypoints(const Map& map, const TrackSpec& spec, TrackReport& rep) {
  const auto& w = map.waypoints;
  const std::size_t n = w.size();
  rep.min_spacing_m = std::numeric_limits<double>::infinity();
  std::size_t min_at = 0;
  std::size_t max_at = 0;
  double sum = 0.0;
  double area2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Waypoint& a = w[i];
    const Waypoint& b = w[(i + 1) % n];
    const double gap = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    sum += gap;
    if (gap < rep.min_spacing_m) {
      rep.min_spacing_m = gap;
      min_at = i;
    }
    if (gap > rep.max_spacing_m) {
      rep.max_spacing_m = gap;
      max_at = i;
    }
    area2 += a.x_m * b.y_m - b.x_m * a.y_m;
    rep.max_abs_coordinate_m =
        std::max({rep.max_abs_coordinate_m, std::abs(a.x_m), std::abs(a.y_m)});
  }
  rep.mean_spacing_m = sum / static_cast<double>(n);
  rep.counter_clockwise = area2 > 0.0;

  double along = 0.0;
  for (std::size_t i = 1; i < n; ++i) {
    along += std::hypot(w[i].x_m - w[i - 1].x_m, w[i].y_m - w[i - 1].y_m);
    rep.max_s_error_m = std::max(rep.max_s_error_m, std::abs(w[i].s_m - w[0].s_m - along));
  }

  auto pair_name = [n](std::size_t i) {
    return "waypoints " + std::to_string(i + 1) + " and " + std::to_string((i + 1) % n + 1);
  };
  if (std::abs(rep.length_m - spec.length_m) > kLengthTolerance * spec.length_m) {
    rep.problems.push_back("length_m: the loop is " + num(rep.length_m) + " m long, more than " +
                           num(100.0 * kLengthTolerance, 0) + "% from " + num(spec.length_m) +
                           " m");
  }
  if (rep.min_spacing_m < spec.min_spacing_m) {
    rep.problems.push_back("min_spacing_m: " + pair_name(min_at) + " are " +
                           num(rep.min_spacing_m, 2) + " m apart, under " +
                           num(spec.min_spacing_m) + " m");
  }
  if (rep.max_spacing_m > spec.max_spacing_m) {
    rep.problems.push_back("max_spacing_m: " + pair_name(max_at) + " are " +
                           num(rep.max_spacing_m, 2) + " m apart, over " + num(spec.max_spacing_m) +
                           " m");
  }
  const double coordinate_limit = max_abs_coordinate_for(spec);
  if (rep.max_abs_coordinate_m >= coordinate_limit) {
    rep.problems.push_back(
        "max_abs_coordinate_m: a waypoint has |x| or |y| = " + num(rep.max_abs_coordinate_m) +
        " m, not under " + num(coordinate_limit) + " m");
  }
  if (!rep.counter_clockwise) {
    rep.problems.push_back("direction: the loop runs clockwise; it must run counter-clockwise");
  }
  if (rep.max_s_error_m > kMaxSErrorM) {
    rep.problems.push_back("s: a waypoint's s is " + num(rep.max_s_error_m, 3) +
                           " m off the straight-line distance from the first waypoint");
  }
}

void check_line(const Map& map, const ReferenceLine& line, const TrackSpec& spec,
                TrackReport& rep) {
  const double length = line.length_m();
  const double s0 = line.start_s_m();

  // Normals: to the right of travel, along the line's.
  bool normals_left = false;
  for (const Waypoint& w : map.waypoints) {
    const RoadFrame f = line.frame(w.s_m);
    const Vec2 n{w.dx, w.dy};
    const double c = dot(right_of(f.tangent), (1.0 / norm(n)) * n);
    if (c < 0.0) normals_left = true;
    rep.max_normal_error_deg = std::max(rep.max_normal_error_deg,
                                        rad_to_deg(std::acos(std::clamp(std::abs(c), 0.0, 1.0))));
  }
  if (normals_left) {
    rep.problems.push_back(
        "normals: (dx, dy) point left of the direction of travel; they must point right, away "
        "from the divider");
  }
  if (rep.max_normal_error_deg > kMaxNormalErrorDeg) {
    rep.problems.push_back("normals: a waypoint's (dx, dy) is " + num(rep.max_normal_error_deg) +
                           " degrees off the road's normal");
  }

  // Radii on the divider, every lane centre and the outer edge; bends at the road's centre.
  std::vector<double> offsets{0.0};
  for (int k = 0; k < spec.road.lane_count; ++k) offsets.push_back(lane_center_d(k, spec.road));
  offsets.push_back(road_width_m(spec));
  const double centre_d = 0.5 * road_width_m(spec);
  const double bend_k = 1.0 / spec.bend_radius_m;
  const auto samples = static_cast<std::size_t>(std::ceil(length / kCurvatureStepM));
  double max_k = 0.0;
  double max_k_d = 0.0;
  rep.min_radius_s_m = s0;
  rep.start_straight_m = length;
  for (std::size_t i = 0; i < samples; ++i) {
    const double along = length * static_cast<double>(i) / static_cast<double>(samples);
    const double s = s0 + along;
    for (const double d : offsets) {
      const double k = std::abs(line.curvature_at(s, d));
      if (k > max_k) {
        max_k = k;
        max_k_d = d;
        rep.min_radius_s_m = s;
      }
    }
    const double kc = line.curvature_at(s, centre_d);
    if (kc > bend_k) rep.bends_left = true;
    if (kc < -bend_k) rep.bends_right = true;
    if (std::abs(kc) > bend_k && along < rep.start_straight_m) rep.start_straight_m = along;
  }
  rep.min_radius_m = max_k > 0.0 ? 1.0 / max_k : std::numeric_limits<double>::infinity();
  if (rep.min_radius_m < spec.min_radius_m) {
    rep.problems.push_back("min_radius_m: radius " + num(rep.min_radius_m) +
                           " m at s = " + num(rep.min_radius_s_m) + " m, d = " + num(max_k_d) +
                           " m, under " + num(spec.min_radius_m) + " m");
  }
  if (!rep.bends_left) {
    rep.problems.push_back("bends: no left bend (radius under " + num(spec.bend_radius_m, 0) +
                           " m)");
  }
  if (!rep.bends_right) {
    rep.problems.push_back("bends: no right bend (radius under " + num(spec.bend_radius_m, 0) +
                           " m)");
  }
  const double start_needed = required_start_straight_m(spec);
  if (rep.start_straight_m < start_needed) {
    rep.problems.push_back("start_straight_m: the road bends " + num(rep.start_straight_m) +
                           " m after the first waypoint, before " + num(start_needed) + " m");
  }

  // Clearance between distant stretches (road band around its centre line) and crossings of
  // the divider line.
  const std::size_t m = std::clamp<std::size_t>(
      static_cast<std::size_t>(std::ceil(length / kPairStepM)), 16, kMaxPairSamples);
  const double step = length / static_cast<double>(m);
  const double half_width = centre_d + spec.shoulder_m;
  std::vector<Vec2> divider(m);
  std::vector<Vec2> centre(m);
  double max_segment = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    const double s = s0 + step * static_cast<double>(i);
    divider[i] = line.frame(s).position;
    centre[i] = line.to_cartesian({s, centre_d});
  }
  for (std::size_t i = 0; i < m; ++i) {
    max_segment = std::max(max_segment, distance(divider[i], divider[(i + 1) % m]));
  }
  const double cross_reach_sq = 4.0 * max_segment * max_segment;
  double min_gap_sq = std::numeric_limits<double>::infinity();
  std::size_t gap_i = 0;
  std::size_t gap_j = 0;
  std::optional<std::pair<std::size_t, std::size_t>> crossing;
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = i + 1; j < m; ++j) {
      const std::size_t apart = std::min(j - i, m - (j - i));
      const double along = step * static_cast<double>(apart);
      const double dc = distance_sq(centre[i], centre[j]);
      const double distinct = kDistinctChordFraction * along;
      if (dc < distinct * distinct && dc < min_gap_sq) {
        min_gap_sq = dc;
        gap_i = i;
        gap_j = j;
      }
      if (!crossing && apart >= 2 && distance_sq(divider[i], divider[j]) <= cross_reach_sq &&
          segments_cross(divider[i], divider[(i + 1) % m], divider[j], divider[(j + 1) % m])) {
        crossing = std::pair{i, j};
      }
    }
  }
  rep.min_clearance_m = std::isfinite(min_gap_sq) ? std::sqrt(min_gap_sq) - 2.0 * half_width
                                                  : std::numeric_limits<double>::infinity();
  if (crossing) {
    rep.self_intersecting = true;
    rep.problems.push_back("self-intersecting: the divider line crosses itself near s = " +
                           num(s0 + step * static_cast<double>(crossing->first)) + " m and s = " +
                           num(s0 + step * static_cast<double>(crossing->second)) + " m");
  }
  if (rep.min_clearance_m < spec.min_clearance_m) {
    rep.problems.push_back(
        "min_clearance_m: the road at s = " + num(s0 + step * static_cast<double>(gap_i)) +
        " m and s = " + num(s0 + step * static_cast<double>(gap_j)) + " m is " +
        num(rep.min_clearance_m) + " m apart edge to edge, under " + num(spec.min_clearance_m) +
        " m");
  }
}

}  // namespace

void validate_track_spec(const TrackSpec& spec) {
  validate_check_spec(spec);
  if (spec.length_m < kMinLoopLengthM) {
    bad_field("length_m", "must be at least " + num(kMinLoopLengthM, 0) + " m (got " +
                              num(spec.length_m) + ")");
  }
  if (spec.length_m > kMaxLoopLengthM) {
    bad_field("length_m",
              "must be at most " + num(kMaxLoopLengthM, 0) + " m (got " + num(spec.length_m) + ")");
  }
  if (spec.length_m < kMinLengthPerMinRadius * spec.min_radius_m) {
    bad_field("length_m", "a loop of " + num(spec.length_m) + " m has no room for bends of " +
                              "min_radius_m = " + num(spec.min_radius_m) + " m (it needs " +
                              num(kMinLengthPerMinRadius, 0) + " times that)");
  }
  if (spec.min_spacing_m > kMaxMinSpacingPerRadius * spec.min_radius_m) {
    bad_field("min_spacing_m",
              "waypoints " + num(spec.min_spacing_m) +
                  " m apart cannot follow bends of min_radius_m = " + num(spec.min_radius_m) +
                  " m (at most " + num(kMaxMinSpacingPerRadius * spec.min_radius_m) + " m)");
  }
  if (spec.max_spacing_m < kMinSpacingRatio * spec.min_spacing_m) {
    bad_field("max_spacing_m", "must be at least " + num(kMinSpacingRatio) +
                                   " times min_spacing_m to place waypoints");
  }
  const double box = max_abs_coordinate_for(spec) - road_width_m(spec) - spec.shoulder_m;
  if (8.0 * box < spec.length_m) {
    bad_field("max_abs_coordinate_m", "a box of +-" + num(max_abs_coordinate_for(spec)) +
                                          " m is too small for a loop of " + num(spec.length_m) +
                                          " m");
  }
}

double max_abs_coordinate_for(const TrackSpec& spec) {
  if (spec.max_abs_coordinate_m > 0.0) return spec.max_abs_coordinate_m;
  return kSmallLoopMaxCoordinateM * std::max(1.0, spec.length_m / kSmallLoopLengthM);
}

std::vector<Waypoint> generate_track(const TrackSpec& spec) {
  validate_track_spec(spec);
  const std::string name = "generated track (seed " + std::to_string(spec.seed) + ")";
  std::string last = "no shape fitted the box";
  for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
    const auto w = attempt_track(
        spec, derive_seed(spec.seed, kShapeStream + static_cast<std::uint64_t>(attempt)));
    if (!w) continue;
    try {
      const Map map = parse_map(format_map(*w), name);
      const TrackReport rep = check_track(map, spec);
      if (rep.ok()) return *w;
      last = rep.problems.front();
    } catch (const MapError& e) {
      last = e.what();
    }
  }
  throw std::runtime_error("generate_track: no loop met the spec in " +
                           std::to_string(kMaxAttempts) + " attempts (seed " +
                           std::to_string(spec.seed) + "); last problem: " + last);
}

TrackReport check_track(const Map& map, const TrackSpec& spec) {
  validate_check_spec(spec);
  TrackReport rep;
  rep.length_m = map.loop_length_m;
  if (map.waypoints.size() < 3) {
    rep.problems.push_back("waypoints: a loop needs at least 3, the map has " +
                           std::to_string(map.waypoints.size()));
    return rep;
  }
  check_waypoints(map, spec, rep);
  std::optional<ReferenceLine> line;
  try {
    line.emplace(map);
  } catch (const MapError& e) {
    rep.problems.push_back(std::string("reference line: ") + e.what());
    return rep;
  }
  check_line(map, *line, spec, rep);
  return rep;
}

}  // namespace overtake::core
