#pragma once
// DirectSensitivityObserver — Algorithm 2 run alongside the generalized-α primal solve. After
// each converged step it forms the predictors (33)–(35) for all design variables at once,
// computes the pseudo-loads, back-solves all of them with the factorization of the step's last
// Newton iteration (one call, no new factorization) — by default refined against, or
// refactorized at, the converged state (BackSolveOptions) — and applies the updates (38)–(40):
//   a*_{n+1,i}  = −((½−β)h² a_{n,i} + h q̇_{n,i} + q_{n,i}) / (βh²)                     (35)
//   q̇*_{n+1,i} = q̇_{n,i} + h(1−γ) a_{n,i} + hγ a*_{n+1,i}                               (33)
//   q̈*_{n+1,i} = ((1−α_m) a*_{n+1,i} + α_m a_{n,i} − α_f q̈_{n,i}) / (1−α_f)             (34)
//   S_t [q_{n+1,i}; λ_{n+1,i}] = −b_i                                                     (37)
//   q̇_{,i} = q̇* + γ' q_{,i},  q̈_{,i} = q̈* + β' q_{,i},  a_{,i} = a* + q_{,i}/(βh²)       (38)–(40)
// with b_i ≈ [∂r/∂p_i + M q̈*_i + C q̇*_i ; k ∂Φ/∂p_i] from one of the PseudoLoad variants.
#include <memory>
#include <vector>

#include "lsmbs/integrators/step_observer.hpp"
#include "lsmbs/sensitivity/response_tracker.hpp"

namespace lsmbs {

/// The right-hand sides b_i of eq. (37) (all variables at once, n × n_v) at a converged state.
class PseudoLoad {
 public:
  virtual ~PseudoLoad() = default;
  /// dv_star, dqdd_star: predictors (nq × n_v). For the consistent start (is_start), the
  /// predictors are zero and the system is the start system [M kΦ_qᵀ; kΦ_q 0].
  virtual void compute(const State& s, const Mat& dv_star, const Mat& dqdd_star, double k,
                       double zeta, Mat& B, SensitivityCounts& counts) = 0;
};

/// Exact: b_i = [∂r/∂p_i (element-local, exact in μ and the scalar parameters) + M q̈*_i + C q̇*_i ;
/// 0].
class AnalyticPseudoLoad : public PseudoLoad {
 public:
  AnalyticPseudoLoad(const Model& m, const ModelParams& p, std::vector<ParamDirection> dirs);
  void compute(const State& s, const Mat& dv_star, const Mat& dqdd_star, double k, double zeta,
               Mat& B, SensitivityCounts& counts) override;

 private:
  const Model& m_;
  const ModelParams& p_;
  std::vector<ParamDirection> dirs_;
  Mat MC_;
  Vec col_;
};

/// Eq. (30)–(32), (36): b_i = [R(q, q̇ + Δ q̇*_i, q̈ + Δ q̈*_i, λ, p + Δp_i) − R(q, q̇, q̈, λ, p)] / Δp_i
/// (forward) or the central version with ±Δp_i. The perturbed parameter sets are computed once
/// per design. Evaluated element-locally by default: elements that p_i does not touch and whose
/// residual is linear in (q̇, q̈) contribute exactly M_e q̈*_i + C_e q̇*_i to the difference
/// quotient (one batched product for all variables); only the touched elements and the
/// rate-nonlinear ones (rigid inertia) are evaluated at the perturbed point. The constraint rows
/// cancel exactly (Φ does not depend on q̇, q̈ or p). `full_residual` evaluates the whole
/// residual 2 n_v (central) or n_v + 1 (forward) times per step, literally as Algorithm 2.
class SemiAnalyticalPseudoLoad : public PseudoLoad {
 public:
  SemiAnalyticalPseudoLoad(const Model& m, const ModelParams& p, std::vector<ModelParams> plus,
                           std::vector<ModelParams> minus, std::vector<double> delta, bool central,
                           const std::vector<ParamDirection>& dirs, bool full_residual);
  void compute(const State& s, const Mat& dv_star, const Mat& dqdd_star, double k, double zeta,
               Mat& B, SensitivityCounts& counts) override;

 private:
  const Model& m_;
  const ModelParams& p_;
  std::vector<ModelParams> plus_, minus_;
  std::vector<double> delta_;
  bool central_, full_;
  std::vector<std::vector<int>> evaluated_;  ///< per variable: touched ∪ rate-nonlinear elements
  State pert_;
  Vec R0_, Rp_, Rm_, vi_, ai_;
  Mat MC_;
};

/// Which matrix the back-solves (37) use. kStepFactor: the factorization handed over by the
/// integrator as it is (the last Newton iteration's, Algorithm 2 literally, or the converged
/// state's when the integrator refactorizes). kExact: S_t assembled at the converged state;
/// the step's factorization serves as a preconditioner of iterative refinement, and when that
/// does not contract to round-off (or the step's only factorization is the predictor's), S_t
/// is factorized anew into the observer's own numeric factorization of the shared analysis.
struct BackSolveOptions {
  enum class Mode { kStepFactor, kExact } mode = Mode::kExact;
  int max_refinement = 6;  ///< refinement iterations before falling back to a factorization
  double accept = 1e-13;  ///< correction/solution (max over columns, ∞-norms) accepted as converged
  double round_off = 1e-9;  ///< stagnation below this level is accepted as round-off

  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
};

class DirectSensitivityObserver : public StepObserver {
 public:
  DirectSensitivityObserver(const Model& m, const ModelParams& p, int nv, PseudoLoad& load,
                            ResponseTracker& tracker, SensitivityCounts& counts,
                            BackSolveOptions back_solve = {});
  void on_start(const State& s0, const Vec& a0, const AlphaCoefficients& c, double k, double zeta,
                const SparseLU* start_factor) override;
  bool on_step(const StepInfo& info) override;
  /// Touches only its own state, the tracker and the counts: may run one step behind on a
  /// worker thread (SensitivityOptions::threads = 2).
  bool concurrent() const override { return true; }

 private:
  const Model& m_;
  const ModelParams& p_;
  int nv_;
  PseudoLoad& load_;
  ResponseTracker& tracker_;
  SensitivityCounts& counts_;
  BackSolveOptions bs_;
  SparseLU own_lu_;  // S_t at the converged state when refinement does not contract
  bool own_lu_shares_ = false;
  void exact_solve(const StepInfo& info);
  Mat dq_, dv_, dqdd_, da_, dl_;  // at t_n
  Mat dvs_, dqdds_, das_, B_;     // workspace
  Mat rhs_, SX_;
  std::vector<double> svals_;
};

}  // namespace lsmbs
