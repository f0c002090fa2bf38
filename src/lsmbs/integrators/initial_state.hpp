#pragma once
// Consistent initial conditions for the index-3 DAE:
//  * project_initial_state: Newton projection of q onto Φ(q, t0) = 0 (minimal-norm
//    correction), so that a case file may place bodies approximately, and of q̇ onto
//    Φ_q q̇ + Φ_t = 0. The velocity correction is the smallest in the metric
//    ‖Δq̇‖²_W = Σ Δẋ² + L² Σ Δθ̇² (L the model's length scale: an angular rate counts as the
//    speed it gives a point at distance L, so that m/s and rad/s are not mixed). Velocities the
//    case gave (`held`) are kept exactly and the others are computed from the constraints;
//    given velocities that contradict the constraints are reported, not changed;
//  * consistent_accelerations: q̈0 and λ0 from the acceleration-level (index-1) system
//      [ M  kΦ_qᵀ ; kΦ_q  0 ] [ q̈0 ; λ0 ] = [ −r(q0, q̇0, 0, 0) ; −k γ ],   Φ̈ = Φ_q q̈ + γ.
// Both reuse the model's pattern and the caller's SparseLU (one symbolic analysis per model).
#include <vector>

#include "lsmbs/core/status.hpp"
#include "lsmbs/linalg/sparse_lu.hpp"
#include "lsmbs/mbs/model.hpp"

namespace lsmbs {

struct ProjectionReport {
  double phi_before = 0, phi_after = 0;  ///< ‖Φ‖∞ before / after
  double vel_before = 0, vel_after = 0;  ///< ‖Φ_q q̇ + Φ_t‖∞
  int iterations = 0;
  /// With held velocities that contradict the constraints: the violated constraint rows, their
  /// violation as a speed (|Φ_q q̇ + Φ_t|_i divided by the W⁻¹-norm of row i of Φ_q) and the held
  /// unknowns that enter them.
  std::vector<int> conflicting_rows, conflicting_held;
  std::vector<double> conflict_speed;
};

/// `held` (size n_q, optional): velocity unknowns to keep as given. When the constraints cannot be
/// met with them kept, the status is kNotConverged with a message naming the violated
/// constraints, `report` lists them, and s.v is left as given.
Status project_initial_state(const Model& model, const ModelParams& p, State& s, SparseLU& lu,
                             double tol, ProjectionReport* report = nullptr,
                             const std::vector<char>* held = nullptr);

/// On success `lu` holds the factorization of [M kΦ_qᵀ; kΦ_q 0] (initial sensitivities reuse it).
Status consistent_accelerations(const Model& model, const ModelParams& p, double k, State& s,
                                SparseLU& lu);

}  // namespace lsmbs
