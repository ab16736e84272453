#pragma once
// Cubic splines: a natural one for planners' local paths, a periodic one for the closed
// reference line.

#include <optional>
#include <span>
#include <vector>

namespace overtake::core {

/// Value and first three derivatives of a spline at one parameter.
struct SplineSample {
  double value = 0.0;
  double d1 = 0.0;
  double d2 = 0.0;
  double d3 = 0.0;
};

/// Cubic polynomial pieces over increasing knots: piece i is
/// c0 + c1 u + c2 u^2 + c3 u^3 with u = t - knot[i].
class PiecewiseCubic {
 public:
  /// Natural cubic spline (zero second derivative at both ends) through (t[i], y[i]).
  /// nullopt when there are fewer than 2 points, sizes differ, a value is not finite or the
  /// knots do not strictly increase.
  [[nodiscard]] static std::optional<PiecewiseCubic> natural(std::span<const double> t,
                                                             std::span<const double> y);

  /// Periodic cubic spline through (t[i], y[i]) with period `period` (> t.back() - t[0]):
  /// the curve closes smoothly from the last point back to the first. nullopt on fewer than
  /// 3 points or knots that do not strictly increase within one period.
  [[nodiscard]] static std::optional<PiecewiseCubic> periodic(std::span<const double> t,
                                                              std::span<const double> y,
                                                              double period);

  /// Periodic smoothing spline (Reinsch): the periodic cubic that minimises
  /// sum (y[i] - f(t[i]))^2 + stiffness * integral f''(t)^2 dt over one period. It passes near
  /// the points rather than through them, so that noise in their values (a map's rounded
  /// coordinates) does not become wiggles of its curvature; stiffness 0 interpolates.
  /// (Units: stiffness is in [t]^3 [y]^0: its fourth root is about the wavelength, over
  /// 2 pi, below which wiggles are damped.) nullopt as for periodic, or on a negative or
  /// non-finite stiffness.
  [[nodiscard]] static std::optional<PiecewiseCubic> periodic_smoothing(std::span<const double> t,
                                                                        std::span<const double> y,
                                                                        double period,
                                                                        double stiffness);

  /// Index of the piece that holds t (clamped to the first or last piece).
  [[nodiscard]] std::size_t piece(double t) const;
  /// Evaluates piece `i` at t (no wrapping).
  [[nodiscard]] SplineSample eval_piece(std::size_t i, double t) const;
  /// Evaluates at t; outside the knots the end pieces are extended.
  [[nodiscard]] SplineSample eval(double t) const { return eval_piece(piece(t), t); }
  [[nodiscard]] double operator()(double t) const { return eval(t).value; }

  [[nodiscard]] double front() const { return knots_.front(); }
  /// The end of the last piece (for a periodic spline: first knot + period).
  [[nodiscard]] double back() const { return knots_.back(); }
  [[nodiscard]] std::span<const double> knots() const { return knots_; }

 private:
  struct Piece {
    double c0, c1, c2, c3;
  };
  static PiecewiseCubic from_second_derivatives(std::span<const double> t,
                                                std::span<const double> y,
                                                std::span<const double> m);
  std::vector<double> knots_;  // pieces + 1 entries
  std::vector<Piece> pieces_;
  // For long splines (a reference line has hundreds of pieces, and is looked up thousands of
  // times a step): buckets of equal width in t over the knots, each with the last piece that
  // starts at or before its lower edge. A lookup starts there and steps to the piece; empty
  // for short splines, which are searched by bisection.
  std::vector<std::size_t> bucket_piece_;
  double buckets_per_t_ = 0.0;
};

}  // namespace overtake::core
