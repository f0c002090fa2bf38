#pragma once
// Consistent initial conditions for the index-3 DAE:
//  * project_initial_state: Newton projection of q onto Φ(q, t0) = 0 (minimal-norm
//    correction) and of q̇ onto Φ_q q̇ + Φ_t = 0, so that a case file may place bodies
//    approximately;
//  * consistent_accelerations: q̈0 and λ0 from the acceleration-level (index-1) system
//      [ M  kΦ_qᵀ ; kΦ_q  0 ] [ q̈0 ; λ0 ] = [ −r(q0, q̇0, 0, 0) ; −k γ ],   Φ̈ = Φ_q q̈ + γ.
// Both reuse the model's pattern and the caller's SparseLU (one symbolic analysis per model).
#include <vector>

#include "lsmbs/core/status.hpp"
#include "lsmbs/linalg/sparse_lu.hpp"
#include "lsmbs/mbs/model.hpp"

namespace lsmbs {

struct ProjectionReport {
  double phi_before = 0, phi_after = 0;       ///< ‖Φ‖∞ before / after
  double vel_before = 0, vel_after = 0;       ///< ‖Φ_q q̇ + Φ_t‖∞
  int iterations = 0;
};

Status project_initial_state(const Model& model, const ModelParams& p, State& s, SparseLU& lu,
                             double tol, ProjectionReport* report = nullptr);

/// On success `lu` holds the factorization of [M kΦ_qᵀ; kΦ_q 0] (initial sensitivities reuse it).
Status consistent_accelerations(const Model& model, const ModelParams& p, double k, State& s,
                                SparseLU& lu);

}  // namespace lsmbs
