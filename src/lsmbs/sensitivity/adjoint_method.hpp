#pragma once
// The discrete adjoint of the generalized-α solution (method "adjoint"; derivation in
// docs/methods.md, "Discrete adjoint"). The forward sensitivities of Algorithm 2 — predictors
// (33)–(35), the linear system (37) with S_t at the converged state, the updates (38)–(40), and
// the consistent start — form one linear recurrence x_{n+1} = A_n x_n + b_n(p) in the state
// derivatives x = (q, q̇, q̈, a, λ)_,p. A scalar response ψ = Σ_n w_nᵀ x_n + ∂ψ/∂p is then
// evaluated backwards: with the adjoint Λ_n of x_n,
//   Λ_N = w_N,   Λ_n = w_n + A_nᵀ Λ_{n+1},   dψ/dp = ∂ψ/∂p + Σ_n Λ_{n+1}ᵀ ∂b_n/∂p,
// one transposed solve S_tᵀ μ = (…) per step for all responses at once, and ∂r/∂p contracted
// with μ once per touched parameter (not per design variable). It differentiates exactly the
// discrete solution direct-analytic differentiates, so both agree to round-off.
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs {

/// Terms of the backward recurrence that a test may drop, to show that each is needed (every
/// flag true: the exact adjoint; the command line and the library always use that).
struct AdjointTerms {
  bool mass = true;                 ///< Mᵀ μ: the inertia of the pseudo-load (M q̈*)
  bool damping = true;              ///< Cᵀ μ: the damping of the pseudo-load (C q̇*)
  bool alpha_f = true;              ///< α_f q̈_n in the predictor (34)
  bool alpha_m = true;              ///< α_m a_n in the predictor (34)
  bool velocity_update = true;      ///< γ' q_,p in the update (38)
  bool acceleration_update = true;  ///< β' q_,p in the update (39)
  bool start = true;                ///< the consistent start's [M kΦ_qᵀ; kΦ_q 0] system
  bool multipliers = true;          ///< responses' ∂f/∂λ (constraint forces)
};

/// The adjoint method with some terms dropped (tests only; see AdjointTerms).
SensitivityResult adjoint_sensitivities(const Study& cs, const Vec& p, const SensitivityOptions& o,
                                        const AdjointTerms& terms);

}  // namespace lsmbs
