#pragma once
// Generalized-α time integration of the index-3 augmented-Lagrangian DAE (7), after the paper's
// Algorithm 1 (Chung & Hulbert 1993; Arnold & Brüls 2007):
//   (1−α_m) a_{n+1} + α_m a_n = (1−α_f) q̈_{n+1} + α_f q̈_n                          (8)
//   q_{n+1} = q_n + h q̇_n + h²(½−β) a_n + h²β a_{n+1}                                (9)
//   q̇_{n+1} = q̇_n + h(1−γ) a_n + hγ a_{n+1}                                          (10)
// coefficients from ρ∞ (11); Newton on [r; kΦ] with the iteration matrix S_t (20) and the
// corrections Δq̇ = γ' Δq, Δq̈ = β' Δq (17)–(18). Predictor: q̈_{n+1} = 0, λ_{n+1} = 0.
// Where it departs from Algorithm 1 as printed (docs/methods.md gives the reasons):
//  - the start is consistent (q̈0, λ0 from the acceleration-level system; consistent_start) and
//    q0, q̇0 are projected on the constraints (project_initial; initial_state.hpp); Algorithm 1
//    starts from zero;
//  - k and ζ of eq. (7) are chosen automatically from the iteration matrix (automatic_scaling);
//  - convergence: per-row residual scales and round-off floors, ‖Φ‖ in length units, and the next
//    Newton correction within tol_q·L, applied before the step is accepted (Algorithm 1 tests
//    one residual norm);
//  - at least min_iter Newton corrections per step; a failed step is retried with halved steps;
//    so is a converged step with an inverted element (det F ≤ 0: a stress-free reflection, a
//    spurious solution of the step equations), or with an element folded within the step (det F
//    ≤ 0 at a corner; docs/methods.md "Inverted elements").
// Sparse KLU: one symbolic analysis per run, numeric (re)factorization per Newton iteration
// (full Newton), or reuse while convergence is fast: within a step (modified Newton) or across
// steps of equal h (modified_across_steps; primal runs of large models), both opt-in.
// With StepObserverOptions::threads = 2, concurrent observers (the direct sensitivities of
// Algorithm 2) run on a worker thread one step behind, each step's factorization alternating
// between two numeric factorizations of the one symbolic analysis.
#include <string>
#include <vector>

#include "lsmbs/core/status.hpp"
#include "lsmbs/integrators/step_observer.hpp"

namespace lsmbs {

/// The options of the method: what a case file's "simulation" section sets. How the observers
/// of a run are served is the caller's choice (StepObserverOptions, step_observer.hpp).
struct GeneralizedAlphaOptions {
  double h = 1e-3;         ///< time step
  double t_end = 1.0;      ///< final time
  double rho_inf = 0.8;    ///< spectral radius at infinite frequency, eq. (11)
  double tol_r = 1e-9;     ///< |r_i| ≤ tol_r · s_i + (round-off floor of row i) for every row i,
                           ///< s_i the sum of the absolute force terms of row i
  double tol_phi = 1e-12;  ///< ‖Φ‖∞ ≤ tol_phi · (model length scale)
  double tol_q = 1e-12;  ///< last Newton correction ‖Δq‖∞ ≤ tol_q · (model length scale)
  double force_floor = 0;  ///< absolute residual tolerance [N] added to every row (0: none)
  int max_iter = 25;
  int min_iter = 1;  ///< ≥ 1: every step factorizes S_t at least once (Algorithm 2 needs it)
  bool consistent_start = true;  ///< false: q̈0 = a0 = 0, λ0 = 0 as Algorithm 1
  bool project_initial = true;   ///< project q0, q̇0 onto the constraint manifold
  /// kFull: factorize S_t at every iteration. kModified: reuse the step's first factorization
  /// while the residual falls fourfold per iteration. kModifiedAcrossSteps: also keep it for the
  /// next steps (same h) until the residual stops falling fourfold; a step that fails with an old
  /// factorization is retried with a fresh one before any halving. The observers then see an old
  /// factorization (sensitivities need SensitivityOptions::matrix converged or refined).
  enum class Newton { kFull, kModified, kModifiedAcrossSteps } newton = Newton::kFull;
  static const char* newton_name(Newton n);
  /// Fill-reducing ordering of the KLU analysis (SparseLU::Ordering; case key "ordering":
  /// "amd" or "nested_dissection").
  SparseLU::Ordering ordering = SparseLU::Ordering::kAmd;
  /// The sparse LU (SparseLU::Solver; case key "linear_solver": "auto", "klu" or "umfpack").
  SparseLU::Solver linear_solver = SparseLU::Solver::kAuto;
  int max_halvings = 6;  ///< step-halving retries of one step (h / 2^k)
  double k = 0;          ///< constraint scaling of eq. (7); 0: automatic
  double zeta = 0;       ///< augmented-Lagrangian penalty of eq. (7); 0: automatic (= k)

  /// Empty string when valid, otherwise "field: what is expected" (the case loader maps the
  /// field to its JSON path).
  std::string validate() const;
};

struct IntegratorSummary {
  bool ok = true;
  bool aborted = false;  ///< an observer asked to stop
  std::string message;   ///< failure description (time, norms, worst unknown)
  double t_reached = 0;
  long steps = 0, newton_iterations = 0, factorizations = 0, residual_evaluations = 0;
  long matrix_evaluations = 0, halvings = 0;
  long fresh_factor_retries =
      0;  ///< steps redone with a fresh factorization (modified_across_steps)
  long increment_rejections = 0;  ///< residual test passed, Newton correction still above tol_q
  /// converged steps rejected (then halved) because an element was inverted (det F ≤ 0)
  long inverted_element_rejections = 0;
  /// converged steps rejected (then halved) because an element folded within the step (det F ≤ 0
  /// at a corner only)
  long folded_element_rejections = 0;
  /// accepted steps whose state has a folded element (det F ≤ 0 at a corner only), and the first
  long folded_element_steps = 0;
  std::string folded_first;
  /// Spatial bodies: the largest |ω| h of an accepted step, the body and time, and the ρ∞ of the
  /// run. Index-3 generalized-α in natural coordinates is stable for a spinning body only up to
  /// an ωh that shrinks as ρ∞ → 1 (docs/methods.md, "Spatial rigid bodies"); warnings() names a
  /// run beyond it.
  double max_omega_h = 0, max_omega_h_t = 0, rho_inf = 0;
  std::string max_omega_h_body;
  /// The stability limit of ωh measured for ρ∞ (0.2 up to 0.6, 0.1 up to 0.8, 0.05 up to 0.9,
  /// 0.03 beyond).
  static double omega_h_limit(double rho_inf);
  /// Wall-time split [s]: `setup` = symbolic analysis, projection and consistent start; then, over
  /// the steps, residual evaluations, iteration-matrix assembly, numeric factorizations,
  /// back-solves.
  struct Seconds {
    double setup = 0, residual = 0, matrix = 0, factor = 0, solve = 0;
  } seconds;
  std::vector<double> halving_times;
  double k = 0, zeta = 0;
  std::string linear_solver;  ///< the solver the run used ("klu", "umfpack" or "amg")
  /// The AMG solver's GMRES iterations over all its solves, and the most one solve took (0 with
  /// a direct LU).
  long linear_iterations = 0, max_linear_iterations = 0;
  /// The AMG solver's preconditioner (BlockAmg::Options::Shape): "bulky" or "thin", "bulky, then
  /// thin" when a bulky solve did not converge and started again as thin; "" with a direct LU.
  std::string linear_preconditioner;
  double force_floor = 0;  ///< largest per-row round-off floor met [N] (residual_floor_N)
  double wall_seconds = 0;
  RunStatus status() const;
  std::string report() const;  ///< outcome and counts, one paragraph
  /// What the user should know of a run that completed (a folded element, …): one line each.
  std::vector<std::string> warnings() const;
};

/// Where a run may be resumed: a converged state on the output grid with its acceleration-like
/// a_n, the scaling of eq. (7) of the run it came from, and its place on that run's grid
/// (t = t_origin + grid · h). The discrete adjoint recomputes its trajectory from these.
struct GridCheckpoint {
  State state;
  Vec acc_like;
  double k = 0, zeta = 0;
  double t_origin = 0;
  long grid = 0;
};

class GeneralizedAlpha {
 public:
  /// `served`: how the observers of run() are served (the factorization they see, threads).
  explicit GeneralizedAlpha(GeneralizedAlphaOptions o, StepObserverOptions served = {})
      : opt_(std::move(o)), served_(served) {}
  /// Integrates from s0 (t, q, q̇; a and λ are computed when consistent_start) to t_end.
  /// `final_state` receives the last converged state. The run is Algorithm 1's loop over named
  /// steps (the .cpp): start (consistent start), then per step predict (8)–(10), newton (19)–(20),
  /// on failure halve_or_fail, then accept (a_{n+1}), notify_observers and next_step.
  IntegratorSummary run(const Model& model, const ModelParams& p, State s0,
                        std::vector<StepObserver*> observers, State* final_state = nullptr);
  /// Continues a run from a checkpoint up to grid step `grid_end` of the same grid, with the same
  /// options and no new start (no projection, no consistent start, the checkpoint's k and ζ):
  /// the steps are those of the run the checkpoint came from, up to round-off. Observers get
  /// on_start with the checkpoint's state (start_factor null), then the steps.
  IntegratorSummary resume(const Model& model, const ModelParams& p, const GridCheckpoint& from,
                           long grid_end, std::vector<StepObserver*> observers,
                           State* final_state = nullptr);
  /// Automatic k = ζ: mean of the non-zero |diagonal| entries of β'M + γ'C_t + K_t over the
  /// position unknowns at s.
  static double automatic_scaling(const Model& model, const ModelParams& p, const State& s,
                                  const AlphaCoefficients& c);

 private:
  GeneralizedAlphaOptions opt_;
  StepObserverOptions served_;
};

/// Round-off floor f_i of each position row of the residual, from the iteration matrix S on
/// `pat` (values `vals`) at positions q: f_i = 16 ε Σ_j |S_ij| max(|q_j|, L). No Newton iteration
/// gets row i below it (docs/methods.md, "Convergence test"); the static solver uses it too.
void row_round_off_floor(const CscPattern& pat, const std::vector<double>& vals, const Vec& q,
                         double L, int nq, Vec& floor);

}  // namespace lsmbs
