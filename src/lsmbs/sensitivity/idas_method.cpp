// IdasSensitivity: SUNDIALS IDAS on the GGL index-2 form, the independent reference
// (integrators/idas_ggl.hpp): forward sensitivities of every response at every output time, or
// the adjoint of the time-integral responses (IDAS quadratures, one backward problem per window
// end).
#include <cmath>

#include "lsmbs/core/error.hpp"
#include "lsmbs/integrators/idas_ggl.hpp"
#include "lsmbs/sensitivity/method.hpp"
#include "lsmbs/sensitivity/response_quadrature.hpp"
#include "lsmbs/sensitivity/response_tracker.hpp"

namespace lsmbs {

using Method = SensitivityOptions::Method;

SensitivityResult IdasSensitivity::run(Study& cs, const Vec& p) const {
  const SensitivityOptions& o = options();
  const Design& d = *cs.design;
  SensitivityResult res;
  ModelParams& params = cs.model->params();
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
                     "the idas-adjoint method differentiates time-integral responses (aggregate "
                     "integral, average, "
                     "average_eq45 or rms), and the case has none");
  if (!quad.empty()) idas.set_quadrature(&quad);
  const IdasGGL::Output out = [&](const State& s, const Mat* dq, const Mat* dv, const Mat* da,
                                  const Mat* dl) {
    tracker.record(s, params, dq, dv, da, dl);
    if (o.progress) o.progress(Progress{"IDAS", s.t, io.t_end, 0, 0});
  };
  const auto st = adjoint ? idas.run_adjoint(cs.initial, d, p, out)
                          : idas.run_with_sensitivities(cs.initial, d, p, out);
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
  return res;
}

}  // namespace lsmbs
