#pragma once
// Approximate first-order optimality (KKT) check at a design of a DesignProblem:
//   ∇f + Σ_j λ_j ∇g_j − ν_lower + ν_upper = 0,  λ_j ≥ 0 on active constraints,
// with variables scaled to [0, 1] and responses scaled as in the optimizer. The multipliers of
// the active constraints (|g_j − ū_j| ≤ tol_active |ū_j|) are fitted by non-negative least
// squares on the free variables (not at a bound); the residual is reported relative to ‖∇f‖.
#include <nlohmann/json.hpp>

#include "lsmbs/optimization/problem.hpp"

namespace lsmbs {

struct KktReport {
  int active_constraints = 0, free_variables = 0, at_lower = 0, at_upper = 0;
  std::vector<double> multipliers;  ///< of the active constraints (scaled problem)
  double stationarity = 0;          ///< ‖∇f + Σλ∇g‖∞ on free variables / ‖∇f‖∞
  double bound_sign_violation = 0;  ///< worst wrong-signed reduced gradient at a bound / ‖∇f‖∞
  nlohmann::json to_json() const;
};

KktReport kkt_report(const DesignProblem& prob, const Evaluation& e, double tol_active = 1e-2,
                     double tol_bound = 1e-6);

}  // namespace lsmbs
