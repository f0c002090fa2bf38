#pragma once
// Approximate first-order optimality (KKT) check at a design of a DesignProblem:
//   ∇f + Σ_j λ_j ∇g_j − ν_lower + ν_upper = 0,  λ_j ≥ 0,  λ_j (g_j − ū_j) = 0,
// with variables scaled to [0, 1] and responses scaled as in the optimizer (f/|f|,
// (g − ū)/scale). An optimizer stops near, not on, its active constraints and bounds, so neither
// is decided by a sharp threshold:
// - the multipliers are the non-negative least-squares fit (Lawson–Hanson) of
//   min ‖∇f + Gλ‖² + Σ_j (λ_j s_j)² over every constraint (s_j its scaled slack): a constraint
//   far from its bound can take a multiplier only by paying for it in complementarity;
// - stationarity is the projected-gradient measure ‖x − P(x − ∇L/‖∇f‖∞)‖∞ on [0, 1]ⁿ: a free
//   variable's reduced gradient, or near a bound the smaller of it and the distance to the bound
//   (exactly 0 at a bound when the gradient pushes outwards);
// - complementarity is max_j λ_j |s_j| / ‖∇f‖∞.
// All three are relative to the objective's largest scaled gradient.
#include <nlohmann/json.hpp>

#include "lsmbs/optimization/problem.hpp"

namespace lsmbs {

struct KktReport {
  /// constraints within tol_active of their bound, variables within tol_bound of a bound (for
  /// the report; the measures below do not depend on these counts)
  int active_constraints = 0, free_variables = 0, at_lower = 0, at_upper = 0;
  std::vector<double> multipliers;  ///< λ_j of every scalar constraint (scaled problem)
  double stationarity = 0;          ///< projected ∇L, ∞-norm, relative to ‖∇f‖∞
  double bound_sign_violation = 0;  ///< worst wrong-signed reduced gradient at a bound / ‖∇f‖∞
  double complementarity = 0;       ///< max_j λ_j |scaled slack_j| / ‖∇f‖∞
  double tolerance = 1e-2;          ///< of the verdict (OptimizationSpec::kkt_tolerance)
  /// stationarity, complementarity and bound_sign_violation all at most `tolerance` (NaN: not)
  bool satisfied() const {
    return stationarity <= tolerance && complementarity <= tolerance &&
           bound_sign_violation <= tolerance;
  }
  nlohmann::json to_json() const;
};

/// The report at e, with the verdict's tolerance of the problem's spec (kkt_tolerance). The
/// objective is scaled by `objective_scale` (the optimizer's |f(p0)|; 0: |f| at e), which sets
/// the multipliers' scale; the verdict does not depend on it.
KktReport kkt_report(const DesignProblem& prob, const Evaluation& e, double tol_active = 1e-2,
                     double tol_bound = 1e-6, double objective_scale = 0);

/// min ‖A x − b‖² subject to x ≥ 0 (Lawson and Hanson, "Solving Least Squares Problems", 1974,
/// algorithm NNLS).
Vec nonnegative_least_squares(const Mat& A, const Vec& b);

}  // namespace lsmbs
