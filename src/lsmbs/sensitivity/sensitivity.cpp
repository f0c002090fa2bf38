#include "lsmbs/sensitivity/sensitivity.hpp"

#include <chrono>
#include <cmath>
#include <exception>
#include <thread>

#include "lsmbs/core/error.hpp"
#include "lsmbs/sensitivity/direct_observer.hpp"
#include "lsmbs/sensitivity/response_quadrature.hpp"
#include "lsmbs/sensitivity/response_tracker.hpp"

namespace lsmbs {

namespace {
using Method = SensitivityOptions::Method;
const std::pair<const char*, Method> kNames[] = {{"semi-analytical", Method::kSemiAnalytical},
                                                 {"semi-analytical-central", Method::kSemiAnalyticalCentral},
                                                 {"direct-analytic", Method::kDirectAnalytic},
                                                 {"fd-forward", Method::kFdForward},
                                                 {"fd-central", Method::kFdCentral},
                                                 {"idas", Method::kIdas},
                                                 {"idas-adjoint", Method::kIdasAdjoint}};
}  // namespace

bool SensitivityOptions::parse(const std::string& s, Method& m) {
  for (const auto& [n, v] : kNames)
    if (s == n) {
      m = v;
      return true;
    }
  return false;
}
const char* SensitivityOptions::name(Method m) {
  for (const auto& [n, v] : kNames)
    if (v == m) return n;
  return "?";
}
std::vector<std::string> SensitivityOptions::names() {
  std::vector<std::string> r;
  for (const auto& [n, v] : kNames) r.push_back(n);
  return r;
}

bool SensitivityOptions::parse_matrix(const std::string& s, Matrix& m) {
  if (s == "last") m = Matrix::kLastIteration;
  else if (s == "converged") m = Matrix::kConverged;
  else if (s == "refined") m = Matrix::kRefined;
  else return false;
  return true;
}
const char* SensitivityOptions::matrix_name(Matrix m) {
  return m == Matrix::kLastIteration ? "last" : m == Matrix::kConverged ? "converged" : "refined";
}

double SensitivityOptions::step(const Design& d, const Vec& p, int i) const {
  if (!relative) return delta;
  return delta * std::max(std::abs(p[i]), 1e-2 * (d.variables[i].upper - d.variables[i].lower));
}

nlohmann::json SensitivityOptions::to_json() const {
  if (is_idas()) return {{"method", name(method)}, {"idas", idas.to_json()}};
  return {{"method", name(method)}, {"delta", delta}, {"delta_mode", relative ? "relative" : "absolute"},
          {"matrix", matrix_name(matrix)}, {"refinement_steps", refinement_steps},
          {"pseudo_load", full_residual ? "full_residual" : "element_local"}, {"threads", threads}};
}

nlohmann::json SensitivityCounts::to_json() const {
  return {{"simulations", simulations},
          {"steps", steps},
          {"newton_iterations", newton_iterations},
          {"factorizations", factorizations},
          {"residual_evaluations", residual_evaluations},
          {"pseudo_load_residuals", pseudo_load_residuals},
          {"element_pseudo_loads", element_pseudo_loads},
          {"mass_damping_products", mass_damping_products},
          {"back_solves", back_solves},
          {"back_solve_rhs", back_solve_rhs},
          {"sensitivity_matrix_assemblies", sensitivity_matrix_assemblies},
          {"refinement_solves", refinement_solves},
          {"sensitivity_factorizations", sensitivity_factorizations},
          {"predictor_matrix_steps", predictor_matrix_steps},
          {"wall_seconds", wall_seconds},
          {"primal_wall_seconds", primal_wall_seconds}};
}

namespace {

void add_primal(SensitivityCounts& c, const IntegratorSummary& s) {
  ++c.simulations;
  c.steps += s.steps;
  c.newton_iterations += s.newton_iterations;
  c.factorizations += s.factorizations;
  c.residual_evaluations += s.residual_evaluations;
}

// Progress label of simulation `k` of `n` ("" for a single run).
std::string run_label(long k, long n) {
  return n > 1 ? "simulation " + std::to_string(k) + "/" + std::to_string(n) : std::string();
}

}  // namespace

std::vector<ResponseSensitivity> simulate_responses_at_current_design(Study& cs, SensitivityCounts& counts, IntegratorSummary* primal,
                                            ProgressLine* line, long n_runs) {
  ResponseTracker tr(cs, std::vector<ParamDirection>(cs.design->size()));
  struct Obs : StepObserver {
    ResponseTracker& tr;
    const ModelParams& p;
    Obs(ResponseTracker& t, const ModelParams& pp) : tr(t), p(pp) {}
    void on_start(const State& s, const Vec&, const AlphaCoefficients&, double k, double, const SparseLU*) override {
      tr.set_scaling(k);
      tr.record(s, p, nullptr, nullptr, nullptr, nullptr);
    }
    bool on_step(const StepInfo& i) override {
      if (i.grid_point) tr.record(*i.state, p, nullptr, nullptr, nullptr, nullptr);
      return true;
    }
  } obs(tr, cs.model->params());
  ProgressObserver prog(line, cs.simulation.t_end, run_label(counts.simulations + 1, n_runs));
  InterruptObserver stop;
  const auto s = GeneralizedAlpha(cs.simulation).run(*cs.model, cs.model->params(), cs.initial, {&obs, &prog, &stop});
  add_primal(counts, s);
  if (primal) *primal = s;
  if (!s.ok) throw NumericalFailure("simulation failed during finite differences: " + s.message);
  if (s.aborted) throw NumericalFailure("simulation stopped at t = " + std::to_string(s.t_reached) + " s");
  return tr.results();
}


std::vector<ResponseSensitivity> simulate_responses(Study& cs, const Vec& p, SensitivityCounts& counts,
                                                    ProgressLine* line) {
  cs.design->apply(p, cs.model->params());
  return simulate_responses_at_current_design(cs, counts, nullptr, line, 1);
}

namespace {

// A result that finished but holds a NaN or an infinity is a numerical failure, never a complete
// run with null entries (a too large --delta can make a perturbed simulation meaningless).
void flag_non_finite(SensitivityResult& res, const Design& d, bool grid_gradients) {
  if (!res.ok) return;
  auto fail = [&](const std::string& what) {
    res.ok = false;
    res.message = what + " is not finite (NaN or infinite): a perturbed or nominal simulation produced a "
                         "meaningless value; try a smaller --delta, or check the response";
  };
  for (const auto& r : res.responses) {
    for (size_t k = 0; k < r.values.size(); ++k)
      if (!std::isfinite(r.values[k])) return fail("the value of response '" + r.name + "'");
    if (!grid_gradients) continue;
    for (Eigen::Index k = 0; k < r.gradient.rows(); ++k)
      for (Eigen::Index i = 0; i < r.gradient.cols(); ++i)
        if (!std::isfinite(r.gradient(k, i)))
          return fail("the derivative of response '" + r.name + "' with respect to '" +
                      d.variables[static_cast<size_t>(i)].name + "'");
  }
  for (const auto& q : res.quadratures) {
    if (!std::isfinite(q.value)) return fail("the IDAS quadrature value of response '" + q.name + "'");
    for (Eigen::Index i = 0; i < q.gradient.size(); ++i)
      if (!std::isfinite(q.gradient[i]))
        return fail("the IDAS quadrature derivative of response '" + q.name + "' with respect to '" +
                    d.variables[static_cast<size_t>(i)].name + "'");
  }
}

SensitivityResult compute_sensitivities_unchecked(Study& cs, const Vec& p, const SensitivityOptions& o);

}  // namespace

SensitivityResult compute_sensitivities(Study& cs, const Vec& p, const SensitivityOptions& o) {
  SensitivityResult res = compute_sensitivities_unchecked(cs, p, o);
  if (!res.ok && interrupted()) {  // stopped by SIGINT/SIGTERM: not a numerical failure
    res.interrupted = true;
    res.message = "interrupted by signal " + std::to_string(interrupted()) + " (" + res.message + ")";
    return res;
  }
  flag_non_finite(res, *cs.design, o.method != SensitivityOptions::Method::kIdasAdjoint);
  return res;
}

namespace {

SensitivityResult compute_sensitivities_unchecked(Study& cs, const Vec& p, const SensitivityOptions& o) {
  if (!cs.design) throw SetupError("design", "sensitivities need a design section (design variables)");
  if (cs.responses.empty()) throw SetupError("responses", "sensitivities need at least one response");
  const auto t0 = std::chrono::steady_clock::now();
  const Design& d = *cs.design;
  const int nv = d.size();
  SensitivityResult res;
  ModelParams& params = cs.model->params();

  if (o.is_idas()) {
    const bool adjoint = o.method == Method::kIdasAdjoint;
    ResponseTracker tracker(cs, d.apply_with_directions(p, params));
    tracker.set_scaling(1.0);  // IDAS carries the physical multipliers
    IdasOptions io = o.idas;
    io.h_out = cs.simulation.h;
    io.t_end = cs.simulation.t_end;
    IdasGGL idas(*cs.model, params, io);
    ResponseQuadrature quad(cs, d.apply_with_directions(p, params), cs.initial.t, io.t_end);
    if (adjoint && quad.empty())
      throw SetupError("responses",
                  "the idas-adjoint method differentiates time-integral responses (aggregate integral, average, "
                  "average_eq45 or rms), and the case has none");
    if (!quad.empty()) idas.set_quadrature(&quad);
    const IdasGGL::Output out = [&](const State& s, const Mat* dq, const Mat* dv, const Mat* da, const Mat* dl) {
      tracker.record(s, params, dq, dv, da, dl);
      if (o.progress) o.progress->update(false, " IDAS t = %.5f s (%3.0f %%)", s.t, 100.0 * s.t / io.t_end);
    };
    const auto st = adjoint ? idas.run_adjoint(cs.initial, d, p, out) : idas.run_with_sensitivities(cs.initial, d, p, out);
    res.ok = st.ok;
    res.message = st.message;
    res.idas = st;
    res.counts.simulations = 1;
    res.counts.steps = st.steps;
    res.counts.residual_evaluations = st.residual_evaluations;
    res.counts.factorizations = st.jacobian_evaluations;
    res.counts.newton_iterations = st.nonlinear_iterations;
    res.responses = tracker.results();
    if (adjoint)  // values only: the adjoint differentiates the quadratures, not the grid aggregates
      for (auto& r : res.responses) r.gradient.setConstant(NAN);
    if (!quad.empty()) res.quadratures = quad.results();
    res.counts.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return res;
  }
  if (o.method == Method::kFdForward || o.method == Method::kFdCentral) {
    d.apply(p, params);
    try {
      const long n_runs = 1 + (o.method == Method::kFdCentral ? 2 : 1) * nv;
      const auto base = simulate_responses_at_current_design(cs, res.counts, &res.primal, o.progress, n_runs);
      res.counts.primal_wall_seconds = res.primal.wall_seconds;
      res.responses = base;
      for (auto& r : res.responses) r.gradient.setZero(static_cast<Eigen::Index>(r.values.size()), nv);
      for (int i = 0; i < nv; ++i) {
        const double h = o.step(d, p, i);
        Vec pp = p;
        pp[i] += h;
        d.apply(pp, params);
        const auto plus = simulate_responses_at_current_design(cs, res.counts, nullptr, o.progress, n_runs);
        std::vector<ResponseSensitivity> minus;
        if (o.method == Method::kFdCentral) {
          Vec pm = p;
          pm[i] -= h;
          d.apply(pm, params);
          minus = simulate_responses_at_current_design(cs, res.counts, nullptr, o.progress, n_runs);
        }
        for (size_t r = 0; r < res.responses.size(); ++r) {
          if (plus[r].values.size() != base[r].values.size())
            throw NumericalFailure("response '" + base[r].name + "' changed its number of steps under perturbation");
          for (size_t k = 0; k < base[r].values.size(); ++k)
            res.responses[r].gradient(static_cast<Eigen::Index>(k), i) =
                o.method == Method::kFdCentral ? (plus[r].values[k] - minus[r].values[k]) / (2 * h)
                                               : (plus[r].values[k] - base[r].values[k]) / h;
        }
      }
    } catch (const NumericalFailure& e) {
      res.ok = false;
      res.message = e.what();
    }
    d.apply(p, params);
  } else {
    if (cs.simulation.newton != GeneralizedAlphaOptions::Newton::kFull &&
        o.matrix == SensitivityOptions::Matrix::kLastIteration)
      throw SetupError("simulation.newton",
                  std::string("\"") + GeneralizedAlphaOptions::newton_name(cs.simulation.newton) +
                      "\" keeps factorizations of earlier iterations or steps, which the last-iteration matrix of "
                      "Algorithm 2 cannot back-solve with: use the sensitivity matrix \"converged\" (the default) or "
                      "\"refined\" (--matrix), or \"newton\": \"full\"");
    auto dirs = d.apply_with_directions(p, params);
    ResponseTracker tracker(cs, dirs);
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
      load = std::make_unique<SemiAnalyticalPseudoLoad>(*cs.model, params, std::move(plus), std::move(minus),
                                                        std::move(delta), central, dirs, o.full_residual);
    }
    BackSolveOptions bs;
    bs.mode = o.matrix == SensitivityOptions::Matrix::kRefined ? BackSolveOptions::Mode::kExact
                                                               : BackSolveOptions::Mode::kStepFactor;
    bs.max_refinement = o.refinement_steps;
    DirectSensitivityObserver obs(*cs.model, params, nv, *load, tracker, res.counts, bs);
    StepObserverOptions served;
    served.factor = o.matrix == SensitivityOptions::Matrix::kConverged ? StepObserverOptions::Factor::kConverged
                                                                        : StepObserverOptions::Factor::kLastIteration;
    served.threads = o.threads;
    ProgressObserver prog(o.progress, cs.simulation.t_end);
    InterruptObserver stop;
    res.primal = GeneralizedAlpha(cs.simulation, served).run(*cs.model, params, cs.initial, {&obs, &prog, &stop});
    add_primal(res.counts, res.primal);
    res.ok = res.primal.ok && !res.primal.aborted;  // aborted: stopped by an observer (an interrupt)
    res.message = res.primal.aborted && res.primal.message.empty()
                      ? "stopped at t = " + std::to_string(res.primal.t_reached) + " s"
                      : res.primal.message;
    res.responses = tracker.results();
    if (o.matrix == SensitivityOptions::Matrix::kLastIteration && res.counts.predictor_matrix_steps > 0)
      res.warnings.push_back(
          "--matrix last: " + std::to_string(res.counts.predictor_matrix_steps) + " of " +
          std::to_string(res.counts.steps) +
          " steps converged in one Newton iteration, so their back-solves used the predictor's matrix (q̈ = 0, "
          "λ = 0): the gradients are not the derivative of the discrete solution (the default --matrix converged is)");
  }
  res.counts.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace

}  // namespace lsmbs
