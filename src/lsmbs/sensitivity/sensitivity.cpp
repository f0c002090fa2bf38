#include "lsmbs/sensitivity/sensitivity.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/sensitivity/method.hpp"
#include "lsmbs/sensitivity/response_tracker.hpp"

namespace lsmbs {

namespace {
using Method = SensitivityOptions::Method;
const std::pair<const char*, Method> kNames[] = {
    {"semi-analytical", Method::kSemiAnalytical},
    {"semi-analytical-central", Method::kSemiAnalyticalCentral},
    {"direct-analytic", Method::kDirectAnalytic},
    {"adjoint", Method::kAdjoint},
    {"adjoint-semi-analytical", Method::kAdjointSemiAnalytical},
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
  if (s == "last")
    m = Matrix::kLastIteration;
  else if (s == "converged")
    m = Matrix::kConverged;
  else if (s == "refined")
    m = Matrix::kRefined;
  else
    return false;
  return true;
}
const char* SensitivityOptions::matrix_name(Matrix m) {
  return m == Matrix::kLastIteration ? "last" : m == Matrix::kConverged ? "converged" : "refined";
}

std::string SensitivityOptions::validate() const {
  if (uses_delta() && (!(delta > 0) || !std::isfinite(delta)))
    return "delta: expected a positive finite step";
  if (refinement_steps < 0) return "refinement_steps: expected a non-negative number of iterations";
  if (threads < 1 || threads > 2) return "threads: expected 1 or 2";
  if (!(adjoint_memory_mb >= 0) || !std::isfinite(adjoint_memory_mb))
    return "adjoint_memory: expected a non-negative number of megabytes (0: no bound)";
  return {};  // the IDAS options are the IDAS driver's to check (IdasOptions::validate)
}

double SensitivityOptions::step(const Design& d, const Vec& p, int i) const {
  if (!relative) return delta;
  return delta * std::max(std::abs(p[i]), 1e-2 * (d.variables[i].upper - d.variables[i].lower));
}

namespace {

// Progress label of simulation `k` of `n` ("" for a single run).
std::string run_label(long k, long n) {
  return n > 1 ? "simulation " + std::to_string(k) + "/" + std::to_string(n) : std::string();
}

}  // namespace

void SensitivityCounts::add_run(const IntegratorSummary& s) {
  ++simulations;
  steps += s.steps;
  newton_iterations += s.newton_iterations;
  factorizations += s.factorizations;
  residual_evaluations += s.residual_evaluations;
}

ModelParams parameters_at(const Study& cs, const Vec& p) {
  ModelParams params = cs.model->params();
  if (cs.design) cs.design->apply(p, params);
  return params;
}

std::vector<ResponseSensitivity> simulate_responses_with(const Study& cs, const ModelParams& params,
                                                         SensitivityCounts& counts,
                                                         IntegratorSummary* primal,
                                                         const ProgressCallback& progress,
                                                         long n_runs) {
  ResponseTracker tr(cs, std::vector<ParamDirection>(cs.design->size()), params);
  struct Obs : StepObserver {
    ResponseTracker& tr;
    const ModelParams& p;
    Obs(ResponseTracker& t, const ModelParams& pp) : tr(t), p(pp) {}
    void on_start(const State& s, const Vec&, const AlphaCoefficients&, double k, double,
                  const SparseLU*) override {
      tr.set_scaling(k);
      tr.record(s, p, nullptr, nullptr, nullptr, nullptr);
    }
    bool on_step(const StepInfo& i) override {
      if (i.grid_point) tr.record(*i.state, p, nullptr, nullptr, nullptr, nullptr);
      return true;
    }
  } obs(tr, params);
  ProgressObserver prog(progress, cs.simulation.t_end, run_label(counts.simulations + 1, n_runs));
  InterruptObserver stop;
  const auto s =
      GeneralizedAlpha(cs.simulation).run(*cs.model, params, cs.initial, {&obs, &prog, &stop});
  counts.add_run(s);
  if (primal) *primal = s;
  if (s.aborted && interrupted())
    throw Interrupted("at t = " + std::to_string(s.t_reached) + " s of a perturbed simulation");
  if (!s.ok) throw NumericalFailure("simulation failed during finite differences: " + s.message);
  if (s.aborted)
    throw NumericalFailure("simulation stopped at t = " + std::to_string(s.t_reached) + " s");
  return tr.results();
}

std::vector<ResponseSensitivity> simulate_responses(const Study& cs, const Vec& p,
                                                    SensitivityCounts& counts,
                                                    const ProgressCallback& progress) {
  return simulate_responses_with(cs, parameters_at(cs, p), counts, nullptr, progress, 1);
}

namespace {

// A result that finished but holds a NaN or an infinity is a numerical failure, never a complete
// run with null entries (a too large --delta can make a perturbed simulation meaningless).
// skip_per_step: per-step responses carry no gradient (adjoint_skip_per_step)
void flag_non_finite(SensitivityResult& res, const Design& d, bool grid_gradients,
                     bool skip_per_step) {
  if (!res.ok) return;
  auto fail = [&](const std::string& what) {
    res.ok = false;
    res.message = what +
                  " is not finite (NaN or infinite): a perturbed or nominal simulation produced a "
                  "meaningless value; try a smaller --delta, or check the response";
  };
  for (const auto& r : res.responses) {
    for (size_t k = 0; k < r.values.size(); ++k)
      if (!std::isfinite(r.values[k])) return fail("the value of response '" + r.name + "'");
    if (!grid_gradients || (skip_per_step && !r.times.empty())) continue;
    for (Eigen::Index k = 0; k < r.gradient.rows(); ++k)
      for (Eigen::Index i = 0; i < r.gradient.cols(); ++i)
        if (!std::isfinite(r.gradient(k, i)))
          return fail("the derivative of response '" + r.name + "' with respect to '" +
                      d.variables[static_cast<size_t>(i)].name + "'");
  }
  for (const auto& q : res.quadratures) {
    if (!std::isfinite(q.value))
      return fail("the IDAS quadrature value of response '" + q.name + "'");
    for (Eigen::Index i = 0; i < q.gradient.size(); ++i)
      if (!std::isfinite(q.gradient[i]))
        return fail("the IDAS quadrature derivative of response '" + q.name +
                    "' with respect to '" + d.variables[static_cast<size_t>(i)].name + "'");
  }
}

}  // namespace

SensitivityResult SensitivityMethod::compute(const Study& cs, const Vec& p) const {
  if (!cs.design)
    throw SetupError("design", "sensitivities need a design section (design variables)");
  if (cs.responses.empty())
    throw SetupError("responses", "sensitivities need at least one response");
  if (auto msg = options_.validate(); !msg.empty()) throw Error("sensitivity option " + msg);
  // a step lost in round-off gives an exact zero (forward) or noise: refused, not reported
  if (options_.uses_delta())
    for (int i = 0; i < cs.design->size(); ++i) {
      const auto& v = cs.design->variables[static_cast<size_t>(i)];
      const double h = options_.step(*cs.design, p, i);
      const double scale = std::max(std::abs(p[i]), 1e-2 * (v.upper - v.lower));
      if (!(h >= 1e-13 * scale))
        throw Error("sensitivity option delta: the step of design variable '" + v.name + "' (" +
                    std::to_string(h) + " at p = " + std::to_string(p[i]) +
                    ") is below 1e-13 of its scale and lost in round-off; use a larger delta");
    }
  const auto t0 = std::chrono::steady_clock::now();
  // this evaluation's own parameters (the study's stay as they are), mapped at p here unless the
  // method maps the design itself
  ModelParams params = maps_design() ? cs.model->params() : parameters_at(cs, p);
  SensitivityResult res = run(cs, p, params);
  for (auto& w : res.primal.warnings()) res.warnings.push_back("primal run: " + w);
  if (auto w = cs.design->coincident_features(p); !w.empty()) res.warnings.push_back(w);
  if (auto w = cs.design->features_outside(p); !w.empty()) res.warnings.push_back(w);
  if (auto w = cs.design->idle_variables(); !w.empty()) res.warnings.push_back(w);
  if (!cs.initial_state_note.empty()) res.warnings.push_back(cs.initial_state_note);
  res.counts.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!res.ok && interrupted()) {  // stopped by SIGINT/SIGTERM: not a numerical failure
    res.interrupted = true;
    res.message =
        "interrupted by signal " + std::to_string(interrupted()) + " (" + res.message + ")";
    return res;
  }
  flag_non_finite(res, *cs.design, grid_gradients(),
                  options_.is_adjoint() && options_.adjoint_skip_per_step);
  return res;
}

std::vector<SensitivityResult> idas_on_grids(const Study& cs, const Vec& p, SensitivityOptions o,
                                             double h_fine, const std::vector<int>& strides,
                                             const Mat* directions) {
  o.method = Method::kIdas;
  if (!cs.design)
    throw SetupError("design", "sensitivities need a design section (design variables)");
  if (cs.responses.empty())
    throw SetupError("responses", "sensitivities need at least one response");
  if (auto msg = o.validate(); !msg.empty()) throw Error("sensitivity option " + msg);
  if (!(h_fine > 0) || strides.empty() ||
      std::any_of(strides.begin(), strides.end(), [](int k) { return k < 1; }))
    throw Error("idas_on_grids: expected h_fine > 0 and positive strides");
  if (directions && (directions->rows() != cs.design->size() || directions->cols() < 1))
    throw Error("idas_on_grids: directions must have a row per design variable");
  const auto t0 = std::chrono::steady_clock::now();
  auto results = IdasSensitivity(o).run_on_grids(cs, p, directions, h_fine, strides);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (auto& res : results) {
    res.counts.wall_seconds = wall;
    if (!res.ok && interrupted()) {
      res.interrupted = true;
      res.message =
          "interrupted by signal " + std::to_string(interrupted()) + " (" + res.message + ")";
      continue;
    }
    if (!directions) {
      flag_non_finite(res, *cs.design, true, false);
      continue;
    }
    for (const auto& r : res.responses)  // along directions: no variable to name
      if (res.ok &&
          (!r.gradient.allFinite() ||
           !Eigen::Map<const Vec>(r.values.data(), static_cast<Eigen::Index>(r.values.size()))
                .allFinite())) {
        res.ok = false;
        res.message = "IDAS: response '" + r.name + "' or a directional derivative is not finite";
      }
  }
  return results;
}

std::unique_ptr<SensitivityMethod> make_sensitivity_method(const SensitivityOptions& o) {
  switch (o.method) {
    case Method::kSemiAnalytical:
    case Method::kSemiAnalyticalCentral:
    case Method::kDirectAnalytic:
      return std::make_unique<DirectSensitivity>(o);
    case Method::kFdForward:
    case Method::kFdCentral:
      return std::make_unique<FiniteDifferenceSensitivity>(o);
    case Method::kIdas:
    case Method::kIdasAdjoint:
      return std::make_unique<IdasSensitivity>(o);
    case Method::kAdjoint:
    case Method::kAdjointSemiAnalytical:
      return std::make_unique<AdjointSensitivity>(o);
  }
  throw std::logic_error("make_sensitivity_method: unknown method");
}

SensitivityResult compute_sensitivities(const Study& cs, const Vec& p,
                                        const SensitivityOptions& o) {
  return make_sensitivity_method(o)->compute(cs, p);
}

RunStatus SensitivityResult::status() const {
  if (interrupted) return RunStatus::kInterrupted;
  return ok ? RunStatus::kComplete : RunStatus::kFailed;
}

std::string SensitivityResult::report() const {
  char b[400];
  std::snprintf(b, sizeof b,
                "sensitivities: %s: %zu responses; %ld simulations, %ld steps, %ld factorizations, "
                "%ld back-solves "
                "(%ld right-hand sides), %.3f s",
                run_status_name(status()), responses.size(), counts.simulations, counts.steps,
                counts.factorizations, counts.back_solves, counts.back_solve_rhs,
                counts.wall_seconds);
  std::string r = b;
  if (!message.empty()) r += "\n  " + message;
  for (const auto& w : warnings) r += "\n  warning: " + w;
  return r;
}

}  // namespace lsmbs
