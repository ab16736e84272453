// The shape of a generated loop as a curvature profile: pieces (straights, arcs, clothoids)
// laid end to end, and the poses along them.

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "track_internal.hpp"

namespace overtake::core::track_detail {
namespace {

constexpr double kIntegrationStepM = 4.0;

double heading_change(const Piece& p, double u) {
  return p.k0_1pm * u + 0.5 * (p.k1_1pm - p.k0_1pm) * u * u / p.length_m;
}

}  // namespace

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

Course::Course(std::vector<Piece> pieces) : pieces_(std::move(pieces)) {
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

Pose Course::pose_at(double s) const {
  const std::size_t i = piece_at(s);
  return advance(pieces_[i], poses_[i], 0.0, s - starts_[i]);
}

double Course::curvature_at(double s) const {
  const std::size_t i = piece_at(s);
  const Piece& p = pieces_[i];
  const double u = std::clamp((s - starts_[i]) / p.length_m, 0.0, 1.0);
  return p.k0_1pm + (p.k1_1pm - p.k0_1pm) * u;
}

std::pair<Vec2, Vec2> Course::bounds() const {
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

std::size_t Course::piece_at(double s) const {
  const auto it = std::upper_bound(starts_.begin(), starts_.end() - 1, s);
  const auto i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - starts_.begin() - 1));
  return std::min(i, pieces_.size() - 1);
}

}  // namespace overtake::core::track_detail
