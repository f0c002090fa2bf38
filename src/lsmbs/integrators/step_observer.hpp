#pragma once
// StepObserver — called after every converged time step with the converged state and the
// factorization of the iteration matrix used in the step's last Newton iteration
// (DESIGN.md §Core interfaces 5). Sensitivity methods (Algorithm 2) and output writers are
// observers; they never see how the integrator or the model work inside.
#include <string>

#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/progress.hpp"
#include "lsmbs/linalg/sparse_lu.hpp"
#include "lsmbs/mbs/model.hpp"

namespace lsmbs {

/// Generalized-α coefficients (eq. 11) and the Newton corrections (17)–(18) for step size h.
struct AlphaCoefficients {
  double rho_inf = 0.8, alpha_m = 0, alpha_f = 0, gamma = 0, beta = 0;
  double h = 0, beta_p = 0, gamma_p = 0;  ///< β' = (1−α_m)/((1−α_f) β h²), γ' = γ/(β h)
  static AlphaCoefficients make(double rho_inf, double h);
};

struct StepInfo {
  int step = 0;                        ///< number of converged steps so far (1 for the first)
  bool grid_point = true;              ///< false for sub-steps created by step halving
  const State* prev = nullptr;         ///< converged state at t_n
  const Vec* prev_acc_like = nullptr;  ///< a_n
  const State* state = nullptr;        ///< converged state at t_{n+1}
  const Vec* acc_like = nullptr;       ///< a_{n+1}
  AlphaCoefficients coef;
  double k = 1, zeta = 0;
  const SparseLU* factor = nullptr;  ///< LU of S_t (eq. 20) from the last Newton iteration
  int newton_iterations = 0;
};

class StepObserver {
 public:
  virtual ~StepObserver() = default;
  /// Called once with the initial state (a = acceleration-like a_0). `start_factor` is the LU of
  /// the consistent-start system [M kΦ_qᵀ; kΦ_q 0] (null for the zero start of Algorithm 1).
  virtual void on_start(const State& /*s0*/, const Vec& /*a0*/, const AlphaCoefficients&,
                        double /*k*/, double /*zeta*/, const SparseLU* /*start_factor*/) {}
  /// Return false to stop the integration (the run is then reported as aborted).
  virtual bool on_step(const StepInfo& info) = 0;
  /// True when on_step may run on a worker thread, one step behind the integrator, on a copy of
  /// the step (StepObserverOptions::threads = 2). The observer must then touch nothing the
  /// integrator or the other observers use; its `info.factor` is a second numeric factorization
  /// that the integrator leaves alone until on_step returns. A stop request then takes effect
  /// one step late.
  virtual bool concurrent() const { return false; }
  /// Polled at every Newton iteration: true abandons the step in progress (the run ends at the
  /// last converged step, reported as aborted). Lets an interrupt end a step that would otherwise
  /// spend minutes in Newton iterations and halvings.
  virtual bool stop_requested() const { return false; }
};

/// How an integrator serves its step observers. Chosen by the caller that installs the observers
/// (the sensitivity methods: SensitivityOptions::matrix and ::threads), not by case files.
struct StepObserverOptions {
  /// StepInfo::factor: the factorization of the step's last Newton iteration (the paper's
  /// Algorithm 2, no extra cost), or S_t (20) re-assembled and factorized at the converged state
  /// (the exact Jacobian of the step; one more factorization per step, and none when the run has
  /// no observer).
  enum class Factor { kLastIteration, kConverged };
  Factor factor = Factor::kLastIteration;
  /// 1: observers run on the integrator's thread. 2: observers that declare themselves concurrent
  /// (StepObserver::concurrent) run on a second thread while the next step is computed. The
  /// results are the same to round-off (the two factorizations pivot independently).
  int threads = 1;

  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const {
    return threads < 1 || threads > 2 ? "threads: expected 1 or 2" : "";
  }
};

/// Reports the progress of one time integration to a callback (empty callback: nothing).
class ProgressObserver : public StepObserver {
 public:
  ProgressObserver(ProgressCallback callback, double t_end, std::string label = {})
      : callback_(std::move(callback)) {
    progress_.t_end = t_end;
    progress_.label = std::move(label);
  }
  bool on_step(const StepInfo& i) override {
    if (!callback_) return true;
    progress_.t = i.state->t;
    progress_.step = i.step;
    progress_.newton_iterations = i.newton_iterations;
    callback_(progress_);
    return true;
  }

 private:
  ProgressCallback callback_;
  Progress progress_;
};

/// Stops the integration at the next step, or within the step in progress, once an interrupt
/// (SIGINT, SIGTERM) was requested (core/interrupt.hpp); the run is then reported as aborted.
class InterruptObserver : public StepObserver {
 public:
  bool on_step(const StepInfo&) override { return interrupted() == 0; }
  bool stop_requested() const override { return interrupted() != 0; }
};

}  // namespace lsmbs
