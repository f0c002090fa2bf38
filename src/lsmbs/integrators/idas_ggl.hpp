#pragma once
// IdasGGL — independent reference integrator: SUNDIALS IDAS (variable-order BDF with error
// control) on the Gear–Gupta–Leimkuhler stabilized index-2 form of the same Model:
//   F1 = s₁ (q̇ − v + Φ_qᵀ μ) = 0,  F2 = M v̇ − g + Φ_qᵀ λ = 0,  F3 = s₃ Φ = 0,  F4 = s₄ (Φ_q v + Φ_t) = 0
// with unknowns (q, v, λ, μ); λ and μ are flagged algebraic (IDASetId) and excluded from the
// error test (IDASetSuppressAlg). s₁ = s₄ = κ h_out and s₃ = κ, κ the model's stiffness scale,
// make all rows force-like. The Jacobian F_y + c_j F_ẏ is assembled from the model's blocks into
// a CSC SUNMatrix (pattern fixed) and solved with SUNLinSol_KLU. Consistent y, ẏ come from the
// projection and the acceleration-level system; consistent sensitivity initial values from the
// start system with the model's exact ∂r/∂p. Forward sensitivities (IDASensInit) use either
// IDAS's own difference quotients on the design variables (default, independent of our
// derivative code; μ(p ± δ) cached because IDAS reuses its perturbed points) or the model's
// analytic partials (a sensitivity residual function). Outputs at a fixed grid (the
// generalized-α step times) so that responses are aggregated on the same grid.
#include <functional>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "lsmbs/geometry/design.hpp"
#include "lsmbs/mbs/model.hpp"

namespace lsmbs {

struct IdasOptions {
  double rtol = 1e-6;
  double atol = 1e-9;        ///< times the model length scale (positions) or length/time (velocities)
  double h_out = 1e-3;       ///< output grid
  double t_end = 1.0;
  long max_steps = 500000;
  bool staggered = false;    ///< sensitivity corrector: simultaneous (default) or staggered
  /// true (default): the model's analytic partials; false: IDAS's own difference quotients on p
  /// (these fail with corrector-convergence failures at rtol <= 1e-8 on the slider-crank)
  bool analytic_sensitivity_residual = true;
  static IdasOptions reference();               ///< rtol 1e-9, atol 1e-12
  nlohmann::json to_json() const;
};

struct IdasStats {
  bool ok = true;
  std::string message;
  long steps = 0, residual_evaluations = 0, jacobian_evaluations = 0, nonlinear_iterations = 0;
  long error_test_failures = 0, sensitivity_residual_evaluations = 0;
  double wall_seconds = 0;
  nlohmann::json to_json() const;
};

class IdasGGL {
 public:
  /// Called at t0 and at every output time. dq … dl (n × n_v) are null without sensitivities.
  /// λ in the state is the physical multiplier (k = 1).
  using Output = std::function<void(const State&, const Mat* dq, const Mat* dv, const Mat* da, const Mat* dl)>;

  IdasGGL(const Model& model, const ModelParams& params, IdasOptions o);
  ~IdasGGL();
  /// Primal run from s0 (q, q̇ approximate; projected and completed to consistency).
  IdasStats run(State s0, const Output& out);
  /// With forward sensitivities with respect to the design variables at p.
  IdasStats run_with_sensitivities(State s0, const Design& design, const Vec& p, const Output& out);

  struct Impl;  ///< defined in the .cpp (reached by the C callbacks only)

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace lsmbs
