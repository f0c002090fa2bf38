// IdasSensitivity: SUNDIALS IDAS on the GGL index-2 form, the independent reference
// (integrators/idas_ggl.hpp): forward sensitivities of every response at every output time, or
// the adjoint of the time-integral responses (IDAS quadratures, one backward problem per window
// end).
#include <cmath>

#include "lsmbs/core/error.hpp"
#include "lsmbs/integrators/idas_ggl.hpp"
#include "lsmbs/mbs/parameterization.hpp"
#include "lsmbs/sensitivity/method.hpp"
#include "lsmbs/sensitivity/response_quadrature.hpp"
#include "lsmbs/sensitivity/response_tracker.hpp"

namespace lsmbs {

using Method = SensitivityOptions::Method;

namespace {

// One IDAS run with outputs every h_out; the responses of grid g are recorded at every
// strides[g]-th output (its step strides[g]·h_out). IDAS's steps do not depend on the output
// times (IDA_NORMAL interpolates to them; the stop times are the windows' and law kinks', which
// every grid shares), so each result is what a run on its own grid gives, but for IDAS's initial
// step, which is chosen from h_out.
// `d` at `p`: the study's design, or directions in it (DirectionalParameterization).
// `params`: the study's model parameters, which the run sets to d at p.
std::vector<SensitivityResult> run_idas(const Study& cs, ModelParams& params,
                                        const Parameterization& d, const Vec& p,
                                        const SensitivityOptions& o, double h_out,
                                        const std::vector<int>& strides) {
  const bool adjoint = o.method == Method::kIdasAdjoint;
  std::vector<ResponseTracker> trackers;
  trackers.reserve(strides.size());
  for (size_t g = 0; g < strides.size(); ++g) {
    trackers.emplace_back(cs, d.apply_with_directions(p, params), params);
    trackers.back().set_scaling(1.0);  // IDAS carries the physical multipliers
  }
  IdasOptions io = o.idas;
  io.h_out = h_out;
  io.t_end = cs.simulation.t_end;
  IdasGGL idas(*cs.model, params, io);
  ResponseQuadrature quad(cs, d.apply_with_directions(p, params), params, cs.initial.t, io.t_end);
  if (adjoint && quad.empty())
    throw SetupError("responses",
                     "the idas-adjoint method differentiates time-integral responses (aggregate "
                     "integral, average, "
                     "average_eq45 or rms), and the case has none");
  if (!quad.empty()) idas.set_quadrature(&quad);
  long k_out = 0;  // outputs so far (t0 is output 0)
  const IdasGGL::Output out = [&](const State& s, const Mat* dq, const Mat* dv, const Mat* da,
                                  const Mat* dl) {
    for (size_t g = 0; g < strides.size(); ++g)
      if (k_out % strides[g] == 0) trackers[g].record(s, params, dq, dv, da, dl);
    ++k_out;
    if (o.progress) o.progress(Progress{"IDAS", s.t, io.t_end, 0, 0});
  };
  const auto st = adjoint ? idas.run_adjoint(cs.initial, d, p, out)
                          : idas.run_with_sensitivities(cs.initial, d, p, out);
  std::vector<SensitivityResult> results(strides.size());
  for (size_t g = 0; g < strides.size(); ++g) {
    SensitivityResult& res = results[g];
    res.ok = st.ok;
    res.message = st.message;
    res.idas = st;
    res.counts.simulations = 1;
    res.counts.steps = st.steps;
    res.counts.residual_evaluations = st.residual_evaluations;
    res.counts.factorizations = st.jacobian_evaluations;
    res.counts.newton_iterations = st.nonlinear_iterations;
    res.responses = trackers[g].results();
    if (adjoint)  // values only: the adjoint differentiates the quadratures, not the aggregates
      for (auto& r : res.responses) r.gradient.setConstant(NAN);
    if (!quad.empty()) res.quadratures = quad.results();
  }
  return results;
}

}  // namespace

SensitivityResult IdasSensitivity::run(const Study& cs, const Vec& p, ModelParams& params) const {
  return std::move(run_idas(cs, params, *cs.design, p, options(), cs.simulation.h, {1})[0]);
}

std::vector<SensitivityResult> IdasSensitivity::run_on_grids(
    const Study& cs, const Vec& p, const Mat* directions, double h_fine,
    const std::vector<int>& strides) const {
  ModelParams params = parameters_at(cs, p);
  if (!directions) return run_idas(cs, params, *cs.design, p, options(), h_fine, strides);
  const DirectionalParameterization along(*cs.design, p, *directions);
  return run_idas(cs, params, along, Vec::Zero(directions->cols()), options(), h_fine, strides);
}

}  // namespace lsmbs
