// FiniteDifferenceSensitivity: whole generalized-α re-simulations at p ± h e_i, forward or
// central differences of every response value (the step: SensitivityOptions::step).
#include "lsmbs/core/error.hpp"
#include "lsmbs/sensitivity/method.hpp"

namespace lsmbs {

using Method = SensitivityOptions::Method;

SensitivityResult FiniteDifferenceSensitivity::run(const Study& cs, const Vec& p,
                                                   ModelParams& params) const {
  const SensitivityOptions& o = options();
  const Design& d = *cs.design;
  const int nv = d.size();
  SensitivityResult res;
  try {
    const long n_runs = 1 + (o.method == Method::kFdCentral ? 2 : 1) * nv;
    const auto base =
        simulate_responses_with(cs, params, res.counts, &res.primal, o.progress, n_runs);
    res.counts.primal_wall_seconds = res.primal.wall_seconds;
    res.responses = base;
    for (auto& r : res.responses)
      r.gradient.setZero(static_cast<Eigen::Index>(r.values.size()), nv);
    for (int i = 0; i < nv; ++i) {
      const double h = o.step(d, p, i);
      Vec pp = p;
      pp[i] += h;
      d.apply(pp, params);
      const auto plus =
          simulate_responses_with(cs, params, res.counts, nullptr, o.progress, n_runs);
      std::vector<ResponseSensitivity> minus;
      if (o.method == Method::kFdCentral) {
        Vec pm = p;
        pm[i] -= h;
        d.apply(pm, params);
        minus = simulate_responses_with(cs, params, res.counts, nullptr, o.progress, n_runs);
      }
      for (size_t r = 0; r < res.responses.size(); ++r) {
        if (plus[r].values.size() != base[r].values.size())
          throw NumericalFailure("response '" + base[r].name +
                                 "' changed its number of steps under perturbation");
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
  return res;
}

}  // namespace lsmbs
