#pragma once
// Static equilibrium: Newton on the same model without inertia (q̇ = q̈ = 0),
//   [ K_t  kΦ_qᵀ ; kΦ_q  0 ] [Δq; Δλ] = −[ r(q, 0, 0, λ) ; kΦ ],
// with backtracking on the residual norm. Used for verification (beam theory) and for
// comparisons with quasi-static approaches.
#include <string>

#include "lsmbs/core/status.hpp"
#include "lsmbs/linalg/sparse_lu.hpp"
#include "lsmbs/mbs/model.hpp"

namespace lsmbs {

struct StaticOptions {
  double t = 0;          ///< time at which drivers and loads are evaluated
  double tol_r = 1e-10;  ///< relative to the force scale of the residual's terms
  double tol_phi = 1e-12;
  int max_iter = 50;
  double k = 0;  ///< 0: automatic (mean |diag K_t|)
  /// the sparse LU and its ordering (the case's "simulation" keys of the same names)
  SparseLU::Solver linear_solver = SparseLU::Solver::kAuto;
  SparseLU::Ordering ordering = SparseLU::Ordering::kAmd;

  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
};

struct StaticResult {
  bool ok = false;
  int iterations = 0;
  double residual_norm = 0;
  std::string message;
  std::string linear_solver;  ///< the factorization used ("klu" or "umfpack")
  RunStatus status() const;
  std::string report() const;  ///< outcome and counts, one paragraph
};

/// Invalid options: not ok, with a message naming the option.
StaticResult solve_static(const Model& model, const ModelParams& p, State& s,
                          const StaticOptions& o = {});

}  // namespace lsmbs
