// DirectSensitivity: the direct method of §4.3 (Algorithm 2). The pseudo-load of each design
// variable is either the semi-analytical difference of the residual at p + Δp_i (and p − Δp_i,
// central) and p (eq. 30–32), or the exact element-local ∂r/∂p_i (direct-analytic); the
// back-solves (37) and the updates (38)–(40) run in DirectSensitivityObserver at every step.
#include <exception>
#include <thread>

#include "lsmbs/core/error.hpp"
#include "lsmbs/sensitivity/direct_observer.hpp"
#include "lsmbs/sensitivity/method.hpp"
#include "lsmbs/sensitivity/response_tracker.hpp"

namespace lsmbs {

using Method = SensitivityOptions::Method;

SensitivityResult DirectSensitivity::run(const Study& cs, const Vec& p, ModelParams& params) const {
  const SensitivityOptions& o = options();
  const Design& d = *cs.design;
  const int nv = d.size();
  SensitivityResult res;
  if (cs.simulation.newton != GeneralizedAlphaOptions::Newton::kFull &&
      o.matrix == SensitivityOptions::Matrix::kLastIteration)
    throw SetupError("simulation.newton",
                     std::string("\"") +
                         GeneralizedAlphaOptions::newton_name(cs.simulation.newton) +
                         "\" keeps factorizations of earlier iterations or steps, which the "
                         "last-iteration matrix of "
                         "Algorithm 2 cannot back-solve with: use the sensitivity matrix "
                         "\"converged\" (the default) or "
                         "\"refined\" (--matrix), or \"newton\": \"full\"");
  auto dirs = d.apply_with_directions(p, params);
  ResponseTracker tracker(cs, dirs, params);
  std::unique_ptr<PseudoLoad> load;
  if (o.method == Method::kDirectAnalytic) {
    load = std::make_unique<AnalyticPseudoLoad>(*cs.model, params, dirs);
  } else {
    // perturbed parameter sets μ(p ± Δp_i): computed once per design, never per step
    const bool central = o.method == Method::kSemiAnalyticalCentral;
    std::vector<ModelParams> plus(nv, params), minus(central ? nv : 0, params);
    std::vector<double> delta(nv);
    for (int i = 0; i < nv; ++i) delta[i] = o.step(d, p, i);
    // one volume-fraction map per set (the costly part of the set-up): split over the threads
    auto perturb = [&](int first, int stride) {
      for (int i = first; i < nv; i += stride) {
        Vec pp = p;
        pp[i] += delta[i];
        d.apply(pp, plus[i]);
        if (central) {
          pp[i] = p[i] - delta[i];
          d.apply(pp, minus[i]);
        }
      }
    };
    if (o.threads > 1 && nv > 1) {
      std::exception_ptr err;
      std::thread second([&] {
        try {
          perturb(1, 2);
        } catch (...) {
          err = std::current_exception();
        }
      });
      try {
        perturb(0, 2);
      } catch (...) {
        second.join();
        throw;
      }
      second.join();
      if (err) std::rethrow_exception(err);
    } else {
      perturb(0, 1);
    }
    load = std::make_unique<SemiAnalyticalPseudoLoad>(*cs.model, params, std::move(plus),
                                                      std::move(minus), std::move(delta), central,
                                                      dirs, o.full_residual);
  }
  BackSolveOptions bs;
  bs.mode = o.matrix == SensitivityOptions::Matrix::kRefined ? BackSolveOptions::Mode::kExact
                                                             : BackSolveOptions::Mode::kStepFactor;
  bs.max_refinement = o.refinement_steps;
  DirectSensitivityObserver obs(*cs.model, params, nv, *load, tracker, res.counts, bs);
  StepObserverOptions served;
  served.factor = o.matrix == SensitivityOptions::Matrix::kConverged
                      ? StepObserverOptions::Factor::kConverged
                      : StepObserverOptions::Factor::kLastIteration;
  served.threads = o.threads;
  ProgressObserver prog(o.progress, cs.simulation.t_end);
  InterruptObserver stop;
  res.primal = GeneralizedAlpha(cs.simulation, served)
                   .run(*cs.model, params, cs.initial, {&obs, &prog, &stop});
  res.counts.add_run(res.primal);
  res.ok = res.primal.ok && !res.primal.aborted;  // aborted: stopped by an observer (an interrupt)
  res.message = res.primal.aborted && res.primal.message.empty()
                    ? "stopped at t = " + std::to_string(res.primal.t_reached) + " s"
                    : res.primal.message;
  res.responses = tracker.results();
  if (o.matrix == SensitivityOptions::Matrix::kLastIteration &&
      res.counts.predictor_matrix_steps > 0)
    res.warnings.push_back("--matrix last: " + std::to_string(res.counts.predictor_matrix_steps) +
                           " of " + std::to_string(res.counts.steps) +
                           " steps converged in one Newton iteration, so their back-solves used "
                           "the predictor's matrix (q̈ = 0, "
                           "λ = 0): the gradients are not the derivative of the discrete solution "
                           "(the default --matrix converged is)");
  if (o.method == SensitivityOptions::Method::kSemiAnalytical)
    res.warnings.push_back(
        "semi-analytical (the paper's forward-difference pseudo-loads) is not exact: its "
        "truncation grows with the state sensitivities and is large on free chains of rigid "
        "bodies (docs/verification.md); direct-analytic (the default) and "
        "semi-analytical-central are exact to round-off; --check judges a gradient");
  return res;
}

}  // namespace lsmbs
