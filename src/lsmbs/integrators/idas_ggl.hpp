#pragma once
// IdasGGL — independent reference integrator: SUNDIALS IDAS (variable-order BDF with error
// control) on the Gear–Gupta–Leimkuhler stabilized index-2 form of the same Model (GglSystem,
// ggl_system.hpp):
//   F1 = s₁ (q̇ − v + Φ_qᵀ μ) = 0,  F2 = M v̇ − g + Φ_qᵀ λ = 0,  F3 = s₃ Φ = 0,  F4 = s₄ (Φ_q v +
//   Φ_t) = 0
// with unknowns (q, v, λ, μ); λ and μ are flagged algebraic (IDASetId) and excluded from the
// error test (IDASetSuppressAlg). s₁ = s₄ = κ h_out and s₃ = κ, κ the model's stiffness scale,
// make all rows force-like. The Jacobian F_y + c_j F_ẏ is assembled from the model's blocks into
// a CSC SUNMatrix (pattern fixed) and factorized by SparseLU behind a SUNLinearSolver with
// SUNLinSol_KLU's policy (sundials_handles.hpp). Files: ggl_system.* (the DAE,
// no SUNDIALS), sundials_handles.hpp (RAII), idas_ggl.cpp (forward driver), idas_adjoint.cpp
// (adjoint driver), idas_ggl_impl.hpp (what the two drivers share). Consistent y, ẏ come from the
// projection and the acceleration-level system; consistent sensitivity initial values from the
// start system with the model's exact ∂r/∂p. Forward sensitivities (IDASensInit) use either
// IDAS's own difference quotients on the design variables (default, independent of our
// derivative code; μ(p ± δ) cached because IDAS reuses its perturbed points) or the model's
// analytic partials (a sensitivity residual function). Outputs at a fixed grid (the
// generalized-α step times) so that responses are aggregated on the same grid.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "lsmbs/core/status.hpp"
#include "lsmbs/mbs/model.hpp"
#include "lsmbs/mbs/parameterization.hpp"

namespace lsmbs {

/// Running time integrals Q_k(t) = ∫_{t0}^{t} g_k(y, ẏ) dt integrated by IDAS alongside the
/// DAE (IDAQuadInit) and, with forward sensitivities, dQ_k/dp (IDAQuadSensInit). The integrands
/// are smooth (no window switches inside IDAS); a window [a, b] is Q(b) − Q(a), with IDAS
/// stopping exactly at a and b (`breakpoints()`, IDASetStopTime) to report Q there.
class IdasQuadrature {
 public:
  virtual ~IdasQuadrature() = default;
  virtual int size() const = 0;
  /// Times at which Q (and dQ/dp) are reported through on_breakpoint (t_end always is).
  virtual std::vector<double> breakpoints() const { return {}; }
  /// g(s) for all k (params: the nominal set, or IDAS's perturbed one for difference quotients).
  virtual void integrand(const State& s, const ModelParams& p, double* g) = 0;
  /// dg_k/dp_i = ∂g/∂y y_,i + ∂g/∂ẏ ẏ_,i + ∂g/∂p_i for all k (rows) and design variables i
  /// (columns).
  virtual void integrand_sensitivity(const State& s, const ModelParams& p, const Mat& dq,
                                     const Mat& dv, const Mat& da, const Mat& dl, Mat& dg) = 0;
  /// Q(t) (size()) and, with sensitivities, dQ/dp (size() × n_v; null otherwise). After an
  /// adjoint run, the rows of dQ that were not asked for (needs_gradient) are NaN.
  virtual void on_breakpoint(double t, const Vec& Q, const Mat* dQ) = 0;
  /// Adjoint path: the partial derivatives of g_k at s, ∂g_k/∂q and ∂g_k/∂q̇ (dense, size nq),
  /// and the explicit ∂g_k/∂p (1 × n_v). False (with a reason in `why`) if g_k depends on q̈
  /// or λ, which the adjoint path does not support.
  virtual bool integrand_gradient(int /*k*/, const State& /*s*/, const ModelParams& /*p*/,
                                  Vec& /*gq*/, Vec& /*gv*/, Eigen::RowVectorXd& /*gp*/,
                                  std::string& why) {
    why = "this quadrature has no state gradient";
    return false;
  }
  /// Adjoint path: whether dQ_k(t)/dp is needed at breakpoint (or final time) t. Each (k, t)
  /// asked for costs one backward problem.
  virtual bool needs_gradient(int /*k*/, double /*t*/) const { return true; }
};

struct IdasOptions {
  double rtol = 1e-6;
  /// Absolute tolerance, times the model length scale (positions) or length/time (velocities).
  /// Equal to rtol by default: a coordinate that passes through zero (a rotation angle, a node
  /// near the origin) then gets the accuracy rtol × model size; a much smaller atol makes IDAS
  /// resolve round-off-sized coordinates (docs/methods.md, "IDAS reference path").
  double atol = 1e-6;
  double h_out = 1e-3;  ///< output grid
  double t_end = 1.0;
  long max_steps = 500000;
  /// Maximum BDF order (1–5; 0 = auto: 2 for a model with a flexible body, 5 otherwise). BDF2
  /// is A-stable; BDF3–5 are unstable near the imaginary axis, so an undamped high-frequency
  /// structural mode forces steps of a fraction of its period (docs/methods.md, "IDAS reference
  /// path").
  int max_order = 0;
  /// KLU's partial-pivoting threshold for the GGL iteration matrix (KLU's own default is
  /// 0.001: a diagonal entry is kept as pivot down to 1e-3 of its column's largest). The GGL
  /// matrix mixes rows of very different scale, and a small threshold keeps pivots that spoil the
  /// Newton corrections (docs/methods.md, "IDAS reference path"). 1 is plain partial pivoting.
  double klu_pivot_tolerance = 1.0;
  bool staggered = false;  ///< sensitivity corrector: simultaneous (default) or staggered
  /// Error test on positions and velocities, or on positions only (velocities weighted out). On
  /// an undamped flexible body the velocity error of high structural modes (ω × their tiny
  /// amplitude) forces steps of their period (docs/methods.md, "IDAS reference path"). kAuto:
  /// positions only when the model has a flexible body. Velocities stay accurate through q̇ = v
  /// (F1).
  enum class ErrorTest { kAuto, kPositionsAndVelocities, kPositions };
  ErrorTest error_test = ErrorTest::kAuto;
  /// true (default): the model's analytic partials; false: IDAS's own difference quotients on p
  /// (these fail with corrector-convergence failures at tight tolerances)
  bool analytic_sensitivity_residual = true;
  /// Adjoint runs: forward steps between two checkpoints (IDAAdjInit, Hermite interpolation of
  /// the forward solution in the backward pass); memory ~ this × 2 state vectors.
  long adjoint_checkpoint_steps = 200;
  static IdasOptions reference();  ///< rtol = atol = 1e-9
  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
};

struct IdasStats {
  bool ok = true;
  std::string message;
  long steps = 0, residual_evaluations = 0, jacobian_evaluations = 0, nonlinear_iterations = 0;
  long error_test_failures = 0, nonlinear_convergence_failures = 0,
       sensitivity_residual_evaluations = 0;
  /// velocity DOFs without mass, treated as algebraic variables
  long massless_velocities = 0;
  std::string error_test;  ///< resolved: "positions" or "positions+velocities"
  int max_order = 0;       ///< resolved maximum BDF order
  /// Adjoint runs: backward problems (one per quadrature and time asked for), their steps,
  /// residual and Jacobian evaluations summed, and the checkpoints of the forward pass.
  long adjoint_problems = 0, adjoint_steps = 0, adjoint_residual_evaluations = 0,
       adjoint_jacobian_evaluations = 0;
  long checkpoints = 0;
  double adjoint_wall_seconds = 0;  ///< backward pass (included in wall_seconds)
  double wall_seconds = 0;
  RunStatus status() const;
  std::string report() const;  ///< outcome and counts, one paragraph
};

class IdasGGL {
 public:
  /// Called at t0 and at every output time. dq … dl (n × n_v) are null without sensitivities.
  /// λ in the state is the physical multiplier (k = 1).
  using Output =
      std::function<void(const State&, const Mat* dq, const Mat* dv, const Mat* da, const Mat* dl)>;

  IdasGGL(const Model& model, const ModelParams& params, IdasOptions o);
  ~IdasGGL();
  /// Integrates `q` alongside the next runs (not owned; null: none).
  void set_quadrature(IdasQuadrature* q);
  /// Primal run from s0 (q, q̇ approximate; projected and completed to consistency).
  IdasStats run(State s0, const Output& out);
  /// With forward sensitivities with respect to the design variables at p.
  IdasStats run_with_sensitivities(State s0, const Parameterization& design, const Vec& p,
                                   const Output& out);
  /// Adjoint sensitivities (IDAAdjInit, IDASolveF, IDASolveB with IDAQuadInitB) of the
  /// quadratures Q_k(t) = ∫_{t0}^{t} g_k dt at the breakpoints and t_end where needs_gradient(k,
  /// t), with respect to the design variables at p. The forward pass is a primal run (outputs
  /// without derivatives); each (k, t) is one backward problem started at t on the adjoint of
  /// the GGL system,
  ///   d/dt(F_ẏᵀ ξ) − F_yᵀ ξ = −∂g_kᵀ/∂y,  ξ_q(t) = ξ_v(t) = 0,
  /// with consistent algebraic final values from its hidden constraints (see the .cpp), and
  ///   dQ_k(t)/dp = ∫_{t0}^{t} (∂g_k/∂p − ξᵀ F_p) dt
  /// (the boundary term ξᵀF_ẏ y_p vanishes at t by the final values and at t0 because the
  /// initial positions and velocities do not depend on p). The backward cost does not grow with
  /// the number of design variables; only the quadrature ξᵀ F_p (element-local) does.
  IdasStats run_adjoint(State s0, const Parameterization& design, const Vec& p, const Output& out);

  struct Impl;  ///< idas_ggl_impl.hpp (reached by the C callbacks only)

 private:
  enum class Mode { kPrimal, kForward, kAdjoint };
  IdasStats run_mode(State s0, const Parameterization* design, const Vec& p, const Output& out,
                     Mode mode);
  std::unique_ptr<Impl> impl_;
};

}  // namespace lsmbs
