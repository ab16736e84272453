#include "overtake/core/spline.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseLU>
#include <algorithm>
#include <cassert>
#include <cmath>

namespace overtake::core {
namespace {

bool all_finite(std::span<const double> v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

bool strictly_increasing(std::span<const double> t) {
  for (std::size_t i = 1; i < t.size(); ++i) {
    if (!(t[i] > t[i - 1])) return false;
  }
  return true;
}

/// Splines of at least this many pieces get a bucket index for piece lookups.
constexpr std::size_t kBucketedPieces = 16;

}  // namespace

PiecewiseCubic PiecewiseCubic::from_second_derivatives(std::span<const double> t,
                                                       std::span<const double> y,
                                                       std::span<const double> m) {
  PiecewiseCubic s;
  s.knots_.assign(t.begin(), t.end());
  s.pieces_.reserve(t.size() - 1);
  for (std::size_t i = 0; i + 1 < t.size(); ++i) {
    const double h = t[i + 1] - t[i];
    s.pieces_.push_back({y[i], (y[i + 1] - y[i]) / h - h * (2.0 * m[i] + m[i + 1]) / 6.0,
                         0.5 * m[i], (m[i + 1] - m[i]) / (6.0 * h)});
  }
  if (s.pieces_.size() >= kBucketedPieces) {
    const std::size_t buckets = 2 * s.pieces_.size();
    s.buckets_per_t_ = static_cast<double>(buckets) / (t.back() - t.front());
    s.bucket_piece_.resize(buckets);
    std::size_t i = 0;
    for (std::size_t b = 0; b < buckets; ++b) {
      const double edge = t.front() + static_cast<double>(b) / s.buckets_per_t_;
      while (i + 1 < s.pieces_.size() && t[i + 1] <= edge) ++i;
      s.bucket_piece_[b] = i;
    }
  }
  return s;
}

std::optional<PiecewiseCubic> PiecewiseCubic::natural(std::span<const double> t,
                                                      std::span<const double> y) {
  const std::size_t n = t.size();
  if (n < 2 || y.size() != n || !all_finite(t) || !all_finite(y) || !strictly_increasing(t)) {
    return std::nullopt;
  }
  std::vector<double> m(n, 0.0);
  if (n > 2) {
    // Tridiagonal system for the interior second derivatives (Thomas algorithm).
    const std::size_t k = n - 2;
    std::vector<double> diag(k), upper(k), rhs(k);
    for (std::size_t i = 1; i + 1 < n; ++i) {
      const double h0 = t[i] - t[i - 1];
      const double h1 = t[i + 1] - t[i];
      diag[i - 1] = 2.0 * (h0 + h1);
      upper[i - 1] = h1;
      rhs[i - 1] = 6.0 * ((y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0);
    }
    for (std::size_t i = 1; i < k; ++i) {
      const double lower = t[i + 1] - t[i];  // h of row i's left neighbour
      const double w = lower / diag[i - 1];
      diag[i] -= w * upper[i - 1];
      rhs[i] -= w * rhs[i - 1];
    }
    m[k] = rhs[k - 1] / diag[k - 1];
    for (std::size_t i = k - 1; i-- > 0;) {
      m[i + 1] = (rhs[i] - upper[i] * m[i + 2]) / diag[i];
    }
  }
  return from_second_derivatives(t, y, m);
}

std::optional<PiecewiseCubic> PiecewiseCubic::periodic(std::span<const double> t,
                                                       std::span<const double> y, double period) {
  const std::size_t n = t.size();
  if (n < 3 || y.size() != n || !all_finite(t) || !all_finite(y) || !std::isfinite(period) ||
      !strictly_increasing(t) || !(t.front() + period > t.back())) {
    return std::nullopt;
  }
  std::vector<double> tt(t.begin(), t.end());
  std::vector<double> yy(y.begin(), y.end());
  tt.push_back(t.front() + period);
  yy.push_back(y.front());
  auto h = [&](std::size_t i) { return tt[i + 1] - tt[i]; };  // i in [0, n)

  // Cyclic system: h[i-1] m[i-1] + 2 (h[i-1] + h[i]) m[i] + h[i] m[i+1] = rhs[i], mod n.
  Eigen::SparseMatrix<double> a(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(3 * n);
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t prev = (i + n - 1) % n;
    const std::size_t next = (i + 1) % n;
    const double h0 = h(prev);
    const double h1 = h(i);
    const auto r = static_cast<Eigen::Index>(i);
    entries.emplace_back(r, static_cast<Eigen::Index>(prev), h0);
    entries.emplace_back(r, r, 2.0 * (h0 + h1));
    entries.emplace_back(r, static_cast<Eigen::Index>(next), h1);
    rhs(r) = 6.0 * ((yy[i + 1] - yy[i]) / h1 - (yy[i] - yy[prev]) / h0);
  }
  a.setFromTriplets(entries.begin(), entries.end());
  Eigen::SparseLU<Eigen::SparseMatrix<double>> solver;
  solver.compute(a);
  if (solver.info() != Eigen::Success) return std::nullopt;
  const Eigen::VectorXd sol = solver.solve(rhs);
  if (solver.info() != Eigen::Success) return std::nullopt;
  std::vector<double> m(n + 1);
  for (std::size_t i = 0; i < n; ++i) m[i] = sol(static_cast<Eigen::Index>(i));
  m[n] = m[0];
  return from_second_derivatives(tt, yy, m);
}

std::optional<PiecewiseCubic> PiecewiseCubic::periodic_smoothing(std::span<const double> t,
                                                                 std::span<const double> y,
                                                                 double period, double stiffness) {
  const std::size_t n = t.size();
  if (n < 3 || y.size() != n || !all_finite(t) || !all_finite(y) || !std::isfinite(period) ||
      !strictly_increasing(t) || !(t.front() + period > t.back()) || !std::isfinite(stiffness) ||
      stiffness < 0.0) {
    return std::nullopt;
  }
  std::vector<double> tt(t.begin(), t.end());
  tt.push_back(t.front() + period);
  auto h = [&](std::size_t i) { return tt[i + 1] - tt[i]; };  // i in [0, n)

  // Cyclic band matrices: (Q^T y)_j is the difference of the slopes either side of knot j,
  // R the integrals of products of the hat functions of the second derivative. The spline
  // with values g and second derivatives m satisfies Q^T g = R m; the smoothing one solves
  // (R + stiffness Q^T Q) m = Q^T y and g = y - stiffness Q m.
  const auto ni = static_cast<Eigen::Index>(n);
  Eigen::SparseMatrix<double> q(ni, ni);
  Eigen::SparseMatrix<double> r(ni, ni);
  std::vector<Eigen::Triplet<double>> qe;
  std::vector<Eigen::Triplet<double>> re;
  qe.reserve(3 * n);
  re.reserve(3 * n);
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t prev = (j + n - 1) % n;
    const std::size_t next = (j + 1) % n;
    const double h0 = h(prev);
    const double h1 = h(j);
    const auto c = static_cast<Eigen::Index>(j);
    qe.emplace_back(static_cast<Eigen::Index>(prev), c, 1.0 / h0);
    qe.emplace_back(c, c, -1.0 / h0 - 1.0 / h1);
    qe.emplace_back(static_cast<Eigen::Index>(next), c, 1.0 / h1);
    re.emplace_back(c, c, (h0 + h1) / 3.0);
    re.emplace_back(c, static_cast<Eigen::Index>(next), h1 / 6.0);
    re.emplace_back(static_cast<Eigen::Index>(next), c, h1 / 6.0);
  }
  q.setFromTriplets(qe.begin(), qe.end());
  r.setFromTriplets(re.begin(), re.end());
  Eigen::VectorXd yv(ni);
  for (std::size_t i = 0; i < n; ++i) yv(static_cast<Eigen::Index>(i)) = y[i];
  const Eigen::SparseMatrix<double> qt = q.transpose();
  const Eigen::SparseMatrix<double> a = r + stiffness * (qt * q);
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  solver.compute(a);
  if (solver.info() != Eigen::Success) return std::nullopt;
  const Eigen::VectorXd m = solver.solve(qt * yv);
  if (solver.info() != Eigen::Success) return std::nullopt;
  const Eigen::VectorXd g = yv - stiffness * (q * m);
  std::vector<double> gg(n + 1);
  std::vector<double> mm(n + 1);
  for (std::size_t i = 0; i < n; ++i) {
    gg[i] = g(static_cast<Eigen::Index>(i));
    mm[i] = m(static_cast<Eigen::Index>(i));
  }
  gg[n] = gg[0];
  mm[n] = mm[0];
  return from_second_derivatives(tt, gg, mm);
}

std::size_t PiecewiseCubic::piece(double t) const {
  const std::size_t last = pieces_.size() - 1;
  if (!bucket_piece_.empty() && t >= knots_.front() && t < knots_[last]) {
    // The largest i with knots[i] <= t, as the bisection below finds it: the bucket's piece
    // is a start (its edge may round either way), and the steps make it exact.
    auto b = static_cast<std::size_t>((t - knots_.front()) * buckets_per_t_);
    b = std::min(b, bucket_piece_.size() - 1);
    std::size_t i = bucket_piece_[b];
    while (knots_[i] > t) --i;
    while (knots_[i + 1] <= t) ++i;
    return i;
  }
  const auto it = std::upper_bound(knots_.begin(), knots_.end(), t);
  if (it == knots_.begin()) return 0;
  return std::min<std::size_t>(static_cast<std::size_t>(it - knots_.begin()) - 1,
                               pieces_.size() - 1);
}

SplineSample PiecewiseCubic::eval_piece(std::size_t i, double t) const {
  assert(i < pieces_.size());
  const Piece& p = pieces_[i];
  const double u = t - knots_[i];
  return {p.c0 + u * (p.c1 + u * (p.c2 + u * p.c3)), p.c1 + u * (2.0 * p.c2 + 3.0 * u * p.c3),
          2.0 * p.c2 + 6.0 * u * p.c3, 6.0 * p.c3};
}

}  // namespace overtake::core
