#pragma once
// LevelSet — features combined by Boolean operations (constructive solid geometry, §2.2).
// The combination acts on the normalized values D_i = φ_i/|∇φ_i| (approximate signed
// distances), which leaves the zero level set exactly where the paper's min/max of raw φ puts
// it but gives the result physical units, so that the smoothing band of the Heaviside is a
// length:
//   AND = min (the paper), OR = max, NOT = −D;
//   optional smooth AND/OR by Kreisselmeier–Steinhauser with parameter ks [1/m]:
//     KSmin(D) = m − (1/ks) ln Σ exp(−ks (D_i − m)),  m = min D_i   (and KSmax = −KSmin(−D)).
// evaluate() returns D(x) and ∂D/∂p (chain rule through the affine parameter bindings; through
// the active branch of a min/max) as a sparse list: the features that are active at x only,
// whatever the number of features and variables.
#include <utility>
#include <vector>

#include "lsmbs/geometry/bspline.hpp"
#include "lsmbs/geometry/csg.hpp"
#include "lsmbs/geometry/feature.hpp"

namespace lsmbs {

class LevelSet {
 public:
  LevelSet() = default;
  LevelSet(std::vector<Feature> features, LevelSetNode root, int num_variables);
  const std::vector<Feature>& features() const { return features_; }
  /// The Boolean combination of the features.
  const LevelSetNode& root() const { return root_; }
  int num_variables() const { return nv_; }

  /// Parameter values of every feature at design p, and the curves of its B-splines (call once
  /// per design).
  struct Values {
    std::vector<std::vector<double>> theta;
    std::vector<ClosedBSpline> curves;  ///< per feature; empty unless a B-spline
  };
  Values values(const Vec& p) const;
  /// ∂D/∂p as (variable, value) entries; a variable may appear more than once (the entries sum).
  using Gradient = LevelSetGradient;
  /// D(x); if grad is non-null it is cleared and receives ∂D/∂p. `frozen` (optional, one per
  /// feature): where not NaN, the feature's value is taken as that constant (no derivative)
  /// instead of being evaluated — the mapping freezes features far from an element.
  double evaluate(const Vec2& x, const Values& v, Gradient* grad,
                  const double* frozen = nullptr) const;
  /// Feature f's own distance at x; its derivatives (if grad is non-null) are appended.
  double feature_distance(int f, const Vec2& x, const Values& v, Gradient* grad) const;
  /// Whether an exact (ks = 0) AND/OR of the tree has, at x, a second child within `tol` of the
  /// extremum whose derivative differs: two features coincide there, the combination has a
  /// kink, and its derivative (one child's) is one-sided.
  bool tie_at(const Vec2& x, const Values& v, double tol) const;
  /// Whether feature f is combined by a KS-smoothed and/or (then every child's value weighs in,
  /// also far from its boundary: the mapping never freezes it).
  bool smoothed(int f) const { return smoothed_[static_cast<size_t>(f)]; }
  /// Design variables that parameters of feature f depend on.
  const std::vector<int>& feature_variables(int f) const { return feat_vars_[f]; }
  /// Distances below this are refined to third order (see Feature::distance); the mapping
  /// sets it to a multiple of its smoothing band.
  void set_refine_within(double d) { refine_within_ = d; }
  double refine_within() const { return refine_within_; }
  /// Foot-point iterations of the refined distances (Feature::distance): 0 for the mapping of the
  /// design itself, more where the level set is used away from its zero contour (an offset).
  void set_foot_iterations(int n) { foot_iterations_ = n; }

 private:
  double eval_node(const LevelSetNode& n, const Vec2& x, const Values& v, Gradient* grad,
                   const double* frozen, const double* tie_tol = nullptr,
                   bool* tie = nullptr) const;
  std::vector<Feature> features_;
  LevelSetNode root_;
  int nv_ = 0;
  double refine_within_ = 0;
  int foot_iterations_ = 0;
  std::vector<std::vector<int>> feat_vars_;
  std::vector<bool> smoothed_;
};

}  // namespace lsmbs
