#include "lsmbs/sensitivity/gradient_check.hpp"

#include <cmath>
#include <random>

#include "lsmbs/core/error.hpp"

namespace lsmbs {

nlohmann::json GradientCheckOptions::to_json() const {
  return {{"delta", delta}, {"seed", seed}, {"warn_above", warn}, {"fail_above", fail}};
}

std::string GradientCheckResult::verdict(const GradientCheckOptions& o) const {
  if (!ok || worst > o.fail) return "fail";
  return worst > o.warn ? "warn" : "pass";
}

nlohmann::json GradientCheckResult::to_json(const GradientCheckOptions& o) const {
  nlohmann::json rs = nlohmann::json::object();
  for (const auto& e : entries)
    rs[e.response] = {{"finite_difference", e.finite_difference}, {"method", e.method},
                      {"relative_error", e.relative_error}};
  return {{"options", o.to_json()},
          {"direction", std::vector<double>(direction.data(), direction.data() + direction.size())},
          {"step", std::vector<double>(step.data(), step.data() + step.size())},
          {"responses", rs},
          {"worst", worst},
          {"worst_response", worst_response},
          {"simulations", simulations},
          {"ok", ok},
          {"message", message},
          {"verdict", verdict(o)}};
}

GradientCheckResult check_gradients(Study& cs, const Vec& p, const std::vector<ResponseSensitivity>& gradients,
                                    const GradientCheckOptions& o) {
  if (!cs.design) throw SetupError("design", "a gradient check needs design variables");
  const Design& d = *cs.design;
  const int nv = d.size();
  GradientCheckResult res;
  // random unit direction, reproducible from the seed (a portable generator and transform)
  std::mt19937_64 gen(o.seed);
  res.direction.resize(nv);
  for (int i = 0; i < nv; ++i) {
    // Box–Muller from two uniform doubles in (0, 1]
    const double u1 = (static_cast<double>(gen() >> 11) + 1.0) / 9007199254740992.0;
    const double u2 = static_cast<double>(gen() >> 11) / 9007199254740992.0;
    res.direction[i] = std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
  }
  res.direction /= res.direction.norm();
  Vec scale(nv);
  for (int i = 0; i < nv; ++i)
    scale[i] = std::max(std::abs(p[i]), 1e-2 * (d.variables[i].upper - d.variables[i].lower));
  res.step = o.delta * scale.cwiseProduct(res.direction);

  SensitivityCounts counts;
  std::vector<ResponseSensitivity> plus, minus;
  try {
    plus = simulate_responses(cs, p + res.step, counts);
    minus = simulate_responses(cs, p - res.step, counts);
  } catch (const NumericalFailure& e) {
    res.ok = false;
    res.message = e.what();
  }
  d.apply(p, cs.model->params());
  res.simulations = counts.simulations;
  if (!res.ok) return res;
  const Vec sd = scale.cwiseProduct(res.direction);
  // `gradients` may be any subset of the case's responses (optimize checks the objective and the
  // constraints only): the perturbed runs' responses are matched by name, not by position
  auto by_name = [](const std::vector<ResponseSensitivity>& all, const std::string& name) -> const ResponseSensitivity* {
    for (const auto& x : all)
      if (x.name == name) return &x;
    return nullptr;
  };
  for (size_t r = 0; r < gradients.size(); ++r) {
    const auto& g = gradients[r];
    if (g.gradient.size() == 0 || !g.gradient.allFinite()) continue;
    GradientCheckResult::Entry e;
    e.response = g.name;
    const auto nk = static_cast<Eigen::Index>(g.values.size());
    const ResponseSensitivity* gp = by_name(plus, g.name);
    const ResponseSensitivity* gm = by_name(minus, g.name);
    if (!gp || !gm || gp->values.size() != g.values.size() || gm->values.size() != g.values.size()) {
      res.ok = false;
      res.message = "response '" + g.name + "' changed its number of steps under the check's perturbation";
      return res;
    }
    // A per-step response is judged against its largest directional derivative over the steps (as
    // verify judges gradients against each response's largest): at steps where the derivative
    // nearly vanishes, the central difference's truncation and noise are not small relative to
    // the step's own value (optimize's default check refused the shipped connecting rod's
    // per-step elongation there, at 0.059).
    std::vector<double> Dk(static_cast<size_t>(nk)), Gk(static_cast<size_t>(nk));
    double g_scale = 0, d_scale = 0;
    for (Eigen::Index k = 0; k < nk; ++k) {
      const auto ku = static_cast<size_t>(k);
      Dk[ku] = (gp->values[ku] - gm->values[ku]) / (2 * o.delta);
      Gk[ku] = g.gradient.row(k).dot(sd);
      g_scale = std::max(g_scale, g.gradient.row(k).cwiseProduct(scale.transpose()).norm());
      d_scale = std::max({d_scale, std::abs(Dk[ku]), std::abs(Gk[ku])});
    }
    const double den = std::max(d_scale, 1e-3 * g_scale);
    for (Eigen::Index k = 0; k < nk; ++k) {
      const double D = Dk[static_cast<size_t>(k)], G = Gk[static_cast<size_t>(k)];
      const double rel = den > 0 ? std::abs(D - G) / den : 0.0;
      if (k == 0 || rel > e.relative_error) {  // the signed derivatives of the worst step
        e.finite_difference = D;
        e.method = G;
        e.relative_error = rel;
      }
    }
    if (e.relative_error > res.worst || res.worst_response.empty()) {
      res.worst = std::max(res.worst, e.relative_error);
      if (e.relative_error >= res.worst) res.worst_response = e.response;
    }
    res.entries.push_back(e);
  }
  return res;
}

}  // namespace lsmbs
