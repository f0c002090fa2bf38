#pragma once
// ClosedBSpline — a closed (periodic) uniform cubic B-spline curve, the free-form feature the
// paper names next to circles and ellipses (§2.2, "NURBS"): control points P_0 … P_{n−1},
//   C(t) = Σ_{i=0..3} N_i(u) P_{(k+i) mod n},  t ∈ [0, n), k = ⌊t⌋, u = t − k,
//   N_0 = (1 − u)³/6, N_1 = (3u³ − 6u² + 4)/6, N_2 = (−3u³ + 3u² + 3u + 1)/6, N_3 = u³/6,
// C² everywhere, each span inside the convex hull of its four control points.
// Its level set is the exact signed distance D(x) = ±|x − C(t*)|, t* the closest point,
// positive outside the curve. By the envelope theorem its derivative with respect to a control
// point involves only the four basis functions that are non-zero at t*:
//   ∂D/∂P_j = −N_j(t*) n(t*)        (n the outward unit normal)
// so every sample's gradient has at most 8 entries, whatever the number of control points.
#include <array>
#include <string>
#include <vector>

#include "lsmbs/core/types.hpp"

namespace lsmbs {

class ClosedBSpline {
 public:
  ClosedBSpline() = default;
  /// Control points (x0, y0, x1, y1, …) from θ of size 2n, n ≥ 4.
  ClosedBSpline(const double* theta, int num_points);
  int size() const { return static_cast<int>(P_.size()); }
  const std::vector<Vec2>& control_points() const { return P_; }
  /// Whether the curve runs counter-clockwise (its signed area is positive).
  bool counter_clockwise() const { return ccw_; }

  /// The four control points of the span at t and their basis values (and derivatives).
  void basis(double t, std::array<int, 4>& idx, std::array<double, 4>& N,
             std::array<double, 4>* dN = nullptr, std::array<double, 4>* ddN = nullptr) const;
  Vec2 point(double t) const;
  void eval(double t, Vec2& c, Vec2& d1, Vec2& d2) const;

  /// The closest point of the curve to x.
  struct Foot {
    double t = 0;         ///< its parameter
    double distance = 0;  ///< signed: > 0 outside the curve
    Vec2 normal;          ///< the outward unit normal there
  };
  Foot closest(const Vec2& x) const;

  /// m points per span, in order (a polygon of the curve).
  std::vector<Vec2> polygon(int per_span) const;
  /// Empty if the curve is a simple closed curve with a tangent everywhere, else what is wrong.
  std::string check() const;

 private:
  void eval_span(int k, double u, Vec2& c, Vec2& d1, Vec2& d2) const;
  double local_min(const Vec2& x, int span, double u0, double* dist2) const;
  std::vector<Vec2> P_;
  std::vector<Vec2> samples_;             // kSamples per span
  std::vector<std::array<Vec2, 2>> box_;  // bounding box of each span's control points
  bool ccw_ = true;
};

}  // namespace lsmbs
