#pragma once
// Design sensitivities of the study's responses (§4.3), methods by name (each a class behind
// SensitivityMethod, method.hpp):
//  semi-analytical          Algorithm 2 exactly: predictors (33)–(35), pseudo-load from the
//                           perturbed residual (32) minus the actual residual at p (eq. 30),
//                           back-solves with the step's last factorization, updates (38)–(40);
//  semi-analytical-central  the same with central differences of the residual (±Δp);
//  direct-analytic          the same linear pseudo-problem (37) with exact ∂r/∂p_i
//                           (element-local, from ∂μ_e/∂p_i) plus M q̈*_i + C q̇*_i — no Δp;
//  fd-forward, fd-central   whole re-simulations per design variable;
//  adjoint                  the discrete adjoint of the generalized-α solution (Algorithm 1 as
//                           implemented): the exact gradient of the same discrete solution as
//                           direct-analytic, one transposed solve per step for all responses
//                           at once, whatever the number of variables (adjoint_method.cpp);
//  adjoint-semi-analytical  the same backward pass, ∂r/∂p contracted with the adjoint by a forward
//                           difference of the element residuals (Δp as semi-analytical): the
//                           paper's semi-analytical idea in adjoint form, not exact (O(Δp));
//  idas                     SUNDIALS IDAS forward sensitivities on the GGL index-2 form
//                           (independent reference, integrators/idas_ggl.hpp);
//  idas-adjoint             IDAS adjoint sensitivities (IDASolveB) of the time-integral
//                           responses only (integral, average, average_eq45, rms, as IDAS
//                           quadratures): one backward problem per window end, whatever the
//                           number of design variables. The grid responses get values only
//                           (gradients NaN); the gradients are in `quadratures`.
// Responses are the case's output.responses; their gradients follow eq. (24) at every grid
// step and the aggregation (average eq. 45, per-step eq. 42, max, KS, integral, …).
#include <limits>
#include <string>
#include <vector>

#include "lsmbs/core/progress.hpp"
#include "lsmbs/core/status.hpp"
#include "lsmbs/integrators/idas_ggl.hpp"
#include "lsmbs/sensitivity/study.hpp"

namespace lsmbs {

struct SensitivityOptions {
  enum class Method {
    kSemiAnalytical,
    kSemiAnalyticalCentral,
    kDirectAnalytic,
    kFdForward,
    kFdCentral,
    kIdas,
    kIdasAdjoint,
    kAdjoint,
    kAdjointSemiAnalytical
  };
  bool is_idas() const { return method == Method::kIdas || method == Method::kIdasAdjoint; }
  bool is_adjoint() const {
    return method == Method::kAdjoint || method == Method::kAdjointSemiAnalytical;
  }
  /// Semi-analytical and finite-difference methods: they perturb p by `delta`.
  bool uses_delta() const {
    return method == Method::kSemiAnalytical || method == Method::kSemiAnalyticalCentral ||
           method == Method::kFdForward || method == Method::kFdCentral ||
           method == Method::kAdjointSemiAnalytical;
  }
  Method method = Method::kDirectAnalytic;
  /// Δp of the semi-analytical methods and step of the finite differences:
  /// relative: Δp_i = delta · max(|p_i|, 1e-2 (upper_i − lower_i)); absolute: Δp_i = delta.
  double delta = 1e-6;
  bool relative = true;
  /// Matrix of the back-solves (37). `converged` (default, exact): the integrator refactorizes
  /// S_t at every converged state (one more numeric factorization per step). `refined` (exact):
  /// S_t assembled at the converged state, solved by iterative refinement with the step's last
  /// factorization as preconditioner, or by a new factorization on the sensitivity thread when
  /// that does not contract to round-off (cheaper only with few variables). `last`: the
  /// factorization of the step's last Newton iteration as it is — the paper's Algorithm 2
  /// literally, for comparisons; where a step converged in one Newton iteration it is the
  /// predictor's (q̈ = 0, λ = 0), and the gradient is not the derivative of the discrete solution
  /// (docs/methods.md, "Which matrix").
  enum class Matrix { kLastIteration, kConverged, kRefined };
  Matrix matrix = Matrix::kConverged;
  int refinement_steps = 6;  ///< `refined`: refinement iterations before a new factorization
  /// Semi-analytical pseudo-loads evaluated on the whole residual (Algorithm 2 literally) instead
  /// of element-locally (same result up to round-off, far cheaper; see direct_observer.hpp).
  bool full_residual = false;
  /// Direct and semi-analytical methods: 2 runs the sensitivity update of each step (pseudo-loads,
  /// back-solves, response derivatives) on a second thread while the next step is computed; 1
  /// keeps everything on one thread. Same results to round-off. Not machine-dependent: 2 is
  /// also the default on a one-core machine (it then only interleaves).
  int threads = 2;
  /// Method adjoint: the bound on the memory of the stored trajectory [MB] (0: no bound). A
  /// trajectory that does not fit is stored at checkpoints and recomputed segment by segment in
  /// the backward pass.
  double adjoint_memory_mb = 0;
  /// Methods adjoint*: per-step responses get their values and NaN gradients instead of an error
  /// (optimize sets it when the optimization does not use them; the default refuses them).
  bool adjoint_skip_per_step = false;
  /// IDAS forward sensitivities (method idas): tolerances and options; output grid and final
  /// time are the case's generalized-α h and t_end.
  IdasOptions idas = IdasOptions::reference();
  /// Progress of the simulations (not an option of the method: not recorded).
  ProgressCallback progress;
  /// Empty string when valid, otherwise "field: what is expected". `delta` is checked for the
  /// methods that use it; the IDAS options are the IDAS driver's to check (IdasOptions::validate).
  std::string validate() const;
  static bool parse_matrix(const std::string& s, Matrix& m);
  static const char* matrix_name(Matrix m);

  static bool parse(const std::string& name, Method& m);
  static const char* name(Method m);
  static std::vector<std::string> names();
  double step(const Design& d, const Vec& p, int i) const;
};

struct ResponseSensitivity {
  std::string name;
  std::vector<double> values;  ///< one, or one per grid step for a per-step response
  std::vector<double> times;   ///< per-step responses: the step times
  Mat gradient;                ///< values.size() × n_v
  /// max and min aggregates: the time of the step whose value is taken (Aggregate::extreme_time)
  double extreme_time = std::numeric_limits<double>::quiet_NaN();
};

/// A time-integral response evaluated by IDAS quadratures (see response_quadrature.hpp).
struct QuadratureResponse {
  std::string name;        ///< the response's name
  std::string definition;  ///< e.g. "(Q(b) - Q(a)) / (b - a), Q = integral of tip_deviation dt"
  double t0 = 0, t1 = 0;   ///< window used (clipped to the run)
  double value = 0;
  Eigen::RowVectorXd gradient;  ///< 1 × n_v (empty without sensitivities)
};

struct SensitivityCounts {
  long simulations = 0, steps = 0, newton_iterations = 0, factorizations = 0;
  long residual_evaluations = 0;   ///< primal (Newton) residual evaluations
  long pseudo_load_residuals = 0;  ///< full perturbed residual evaluations (semi-analytical)
  long element_pseudo_loads = 0;   ///< element-local ∂r/∂p evaluations (direct-analytic)
  long mass_damping_products = 0;  ///< M q̈* + C q̇* block products (direct-analytic)
  long back_solves = 0, back_solve_rhs = 0;
  long sensitivity_matrix_assemblies = 0;  ///< S_t at the converged state (refined)
  long refinement_solves = 0;              ///< refined: back-solves of the iterative refinement
  long sensitivity_factorizations = 0;     ///< refined: S_t factorized anew at the converged state
  /// steps whose Newton iteration took one iteration: their last factorization is the
  /// predictor's (what `--matrix last` back-solves with there)
  long predictor_matrix_steps = 0;
  double wall_seconds = 0, primal_wall_seconds = 0;
  /// Method adjoint: transposed back-solves (one per step, all responses at once), the peak
  /// memory of the stored trajectory [bytes], and the steps recomputed from checkpoints.
  long adjoint_solves = 0, adjoint_recomputed_steps = 0;
  double adjoint_memory_bytes = 0;
  /// Adds one generalized-α run (a simulation, its steps, iterations, factorizations, residuals).
  void add_run(const IntegratorSummary& s);
};

struct SensitivityResult {
  bool ok = true;
  /// The run was stopped by an interrupt (SIGINT/SIGTERM, core/interrupt.hpp): ok is false and the
  /// results are partial; not a numerical failure.
  bool interrupted = false;
  std::string message;
  /// Conditions the user should know about, e.g. inexact back-solves with `--matrix last`.
  std::vector<std::string> warnings;
  std::vector<ResponseSensitivity> responses;
  SensitivityCounts counts;
  IntegratorSummary primal;
  IdasStats idas;  ///< methods idas and idas-adjoint only
  /// Methods idas and idas-adjoint: the time-integral responses from IDAS quadratures with
  /// their gradients (IDAQuadSensInit, or the backward problems), the continuous-time
  /// counterparts of the grid aggregates.
  std::vector<QuadratureResponse> quadratures;
  RunStatus status() const;
  std::string report() const;  ///< outcome and counts, one paragraph
};

// The design is a value: an evaluation at p runs with its own copy of the study's model parameters
// with p written in (parameters_at), and the study itself is not changed. Evaluations of one study
// at different designs may therefore run at once, from several threads, and give the results of
// the same evaluations one after the other, bit for bit (tests/integration/concurrency_test.cpp).

/// The study's model parameters with design p written in (the study's own are not changed).
ModelParams parameters_at(const Study& cs, const Vec& p);

/// Response values of one generalized-α simulation at design p (gradients empty). Throws
/// NumericalFailure when the simulation fails.
std::vector<ResponseSensitivity> simulate_responses(const Study& cs, const Vec& p,
                                                    SensitivityCounts& counts,
                                                    const ProgressCallback& progress = {});
/// The same with the model parameters `params` (e.g. parameters_at(cs, p) changed by a step);
/// `primal` receives the integrator summary.
std::vector<ResponseSensitivity> simulate_responses_with(const Study& cs, const ModelParams& params,
                                                         SensitivityCounts& counts,
                                                         IntegratorSummary* primal,
                                                         const ProgressCallback& progress,
                                                         long n_runs);

/// Sensitivities at design p.
SensitivityResult compute_sensitivities(const Study& cs, const Vec& p, const SensitivityOptions& o);

/// Method idas on several output grids from one IDAS run (the time-step study of `lsmbs verify`):
/// outputs every h_fine, result k recorded on the grid of step strides[k]·h_fine. IDAS's steps do
/// not depend on the output grid but through its initial step (chosen from h_fine), so result k
/// agrees with compute_sensitivities on that grid to IDAS's tolerance. With `directions` (n_v ×
/// k), the gradients are the k directional derivatives ∂f/∂p · W (one IDAS sensitivity per
/// column instead of one per variable). o.method is ignored (idas).
std::vector<SensitivityResult> idas_on_grids(const Study& cs, const Vec& p, SensitivityOptions o,
                                             double h_fine, const std::vector<int>& strides,
                                             const Mat* directions = nullptr);

}  // namespace lsmbs
