#pragma once
// Level-set features (§2.2) with φ > 0 in material and φ < 0 in void. In the paper's form
// a feature describes a hole: φ > 0 outside it.
//   ellipse (eq. 41):        φ = √((u/a)² + (v/b)²) − d          params cx, cy, a, b, d, angle
//   super-ellipse (eq. 43):  φ = |u/a|^ξ + |v/b|^η − 1           params cx, cy, a, b, xi, eta,
//   angle circle:                  φ = √(u² + v²) − r                   params cx, cy, r
//   closed B-spline:         the exact signed distance to the curve   params x1, y1, …, xn, yn
//                            (its n ≥ 4 control points; ClosedBSpline)
// with (u, v) = R(−angle)(x − c). A feature with hole = false is a solid inclusion (−φ).
// Each parameter is a constant or an affine function of one design variable,
// value = offset + scale · p_k, so linked and symmetric features are direct (Table 2).
#include <string>
#include <vector>

#include "lsmbs/core/types.hpp"
#include "lsmbs/geometry/dual.hpp"

namespace lsmbs {

struct ParamBinding {
  double offset = 0, scale = 0;
  int variable = -1;  ///< −1: constant (= offset)
  double value(const Vec& p) const { return variable < 0 ? offset : offset + scale * p[variable]; }
};

class Feature {
 public:
  enum class Type { kEllipse, kSuperEllipse, kCircle, kBSpline };
  Feature(std::string name, Type type, std::vector<ParamBinding> params, bool hole);

  /// The parameters' names of a type with a fixed number of them (empty for a B-spline).
  static const std::vector<std::string>& parameter_names(Type t);
  /// The name of parameter i of this feature ("cx", …; "x3", "y3" for a B-spline's third point).
  std::string parameter_name(size_t i) const;
  static Type parse_type(const std::string& s, bool* ok);
  const std::string& name() const { return name_; }
  Type type() const { return type_; }
  bool hole() const { return hole_; }
  const std::vector<ParamBinding>& params() const { return params_; }

  /// Whether distance() is the exact Euclidean signed distance at θ, so that it changes by at
  /// most |Δx| (circles, ellipses with a·d, b·d > 0, B-splines). A super-ellipse's is not: deep
  /// inside, φ/|∇φ| overestimates it without bound, and far outside it underestimates it by up to
  /// the exponent.
  bool exact_distance(const std::vector<double>& theta) const;
  /// For a super-ellipse: a signed lower bound L on the first-order D₀ = ±φ/|∇φ| over the disc
  /// |x − c| ≤ rho, from interval bounds of φ and |∇φ| in the feature's frame: |D₀(x)| ≥ |L| with
  /// the sign of L everywhere in the disc (0 when φ may change sign there, or for other types).
  /// distance() is D₀ itself where |D₀| ≥ refine_within, which lets the mapping freeze far
  /// super-ellipses (DesignMap::map) without an exact distance.
  double far_bound(const Vec2& c, double rho, const std::vector<double>& theta) const;
  /// Empty if the parameter values θ describe a valid feature, else what is wrong.
  std::string check(const std::vector<double>& theta) const;
  std::vector<double> values(const Vec& p) const;

  /// Signed distance estimate D at x for parameter values θ (T = double or Dual over the
  /// feature's parameters): D₀ = φ/|∇φ| (first order); where |D₀| < refine_within, three
  /// Newton projections y ← y − φ∇φ/|∇φ|² onto φ = 0 and D = ±|(x − y)·n(y)| with the sign of
  /// φ(x) (third order near the boundary; blended C² into D₀ between refine_within/2 and
  /// refine_within).
  /// The refinement removes the O(D²) bias of D₀ (e.g. D₀ ≈ s − 2s²/R for a ξ = 5
  /// super-ellipse) that would otherwise shift a smoothed boundary by a fraction of the band.
  /// With foot_iterations > 0 the projected point is moved that many times along the tangent
  /// towards the foot of x and projected again (twice) onto φ = 0: alternating projections that
  /// converge to the closest point of a convex curve, so that the distance is exact also far
  /// from the boundary (a level set offset by several elements, MappingOptions::offset).
  template <class T>
  T distance(const Vec2& x, const T* theta, double refine_within = 0,
             int foot_iterations = 0) const;
  /// A B-spline's distance is not written over Dual: LevelSet evaluates it through its curve
  /// (ClosedBSpline), built once per design, with its sparse exact derivatives.
  /// φ and ∇φ at a (possibly parameter-dependent) point; for a B-spline (T = double only) φ is
  /// its signed distance and ∇φ the outward normal at the closest point.
  template <class T>
  void phi_grad(const T& x, const T& y, const T* theta, T& phi, T& gx, T& gy) const;
  /// Raw φ (for pictures and checks).
  double phi(const Vec2& x, const std::vector<double>& theta) const;

 private:
  std::string name_;
  Type type_;
  std::vector<ParamBinding> params_;
  bool hole_;
};

}  // namespace lsmbs
