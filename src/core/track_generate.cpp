// Generating a loop (generate_track): a shape drawn as a curvature profile, laid out as a
// rounded rectangle, closed at the wanted length inside the box, and sampled into waypoints.

#include "overtake/core/track.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/map.hpp"
#include "overtake/core/random.hpp"
#include "overtake/core/road.hpp"
#include "overtake/core/units.hpp"
#include "track_internal.hpp"

namespace overtake::core {
namespace {

using track_detail::Course;
using track_detail::Piece;
using track_detail::Pose;
using track_detail::required_start_straight_m;

// ---- Tuning (metres unless named otherwise) ----

constexpr int kMaxAttempts = 64;
constexpr std::uint64_t kShapeStream = 0;
constexpr double kReferenceLengthM = 7000.0;  // the shape's lengths scale with length_m / this
constexpr double kRadiusMargin = 1.2;         // bends are drawn this much wider than the limit
constexpr double kMaxCornerRadiusPerLength = 1.0 / 20.0;
constexpr double kMinFreeFraction = 0.04;      // of the loop: straight length left to square it
constexpr double kBehindStartM = 80.0;         // straight before the first waypoint
constexpr double kAfterStartStraightM = 60.0;  // straight beyond start_straight_m
constexpr double kMinRampM = 60.0;             // shortest clothoid into or out of a bend
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
  r.right_lo_m = kRadiusMargin * rmin + road_width_m(spec.road);
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
      max_abs_coordinate_for(spec) - road_width_m(spec.road) - spec.shoulder_m - kBoxMarginM;
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
}  // namespace

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

GeneratedTrack generate_checked_track(const TrackSpec& spec, const std::string& name) {
  GeneratedTrack t;
  t.text = format_map(generate_track(spec));
  t.map = parse_map(t.text, name);
  t.check = check_track(t.map, spec);
  if (!t.check.problems.empty()) {
    std::string msg = "generated track fails its checks:";
    for (const auto& p : t.check.problems) msg += "\n  - " + p;
    throw std::runtime_error(msg);
  }
  return t;
}

}  // namespace overtake::core
