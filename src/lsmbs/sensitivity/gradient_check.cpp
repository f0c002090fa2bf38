#include "lsmbs/sensitivity/gradient_check.hpp"

#include <cmath>
#include <cstdio>
#include <random>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"

namespace lsmbs {

std::string GradientCheckOptions::validate() const {
  auto g = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return std::string(b);
  };
  if (!(delta > 0 && delta < 1))
    return "delta: expected a relative step in (0, 1), got " + g(delta);
  if (!(warn > 0) || !std::isfinite(warn))
    return "warn: expected a positive finite relative disagreement, got " + g(warn);
  if (!(fail >= warn) || !std::isfinite(fail))
    return "fail: expected a finite relative disagreement >= warn (" + g(warn) + "), got " +
           g(fail);
  return {};
}

std::string GradientCheckResult::verdict(const GradientCheckOptions& o) const {
  if (interrupted) return "interrupted";
  if (!ok || worst > o.fail) return "fail";
  return worst > o.warn ? "warn" : "pass";
}

GradientDifference compare_gradients(const std::vector<ResponseSensitivity>& a,
                                     const std::vector<ResponseSensitivity>& reference,
                                     GradientNorm norm) {
  GradientDifference d;
  auto note = [&](double e, const std::string& where) {
    if (e > d.worst) {
      d.worst = e;
      d.where = where;
    }
  };
  if (a.size() != reference.size()) {
    d.worst = INFINITY;
    d.where = std::to_string(a.size()) + " responses against " + std::to_string(reference.size());
    return d;
  }
  for (size_t r = 0; r < reference.size(); ++r) {
    const Mat& A = a[r].gradient;
    const Mat& B = reference[r].gradient;
    const std::string& name = reference[r].name;
    if (A.rows() != B.rows() || A.cols() != B.cols()) {
      d.worst = INFINITY;
      d.where = name + " (gradients of different shapes)";
      return d;
    }
    if (B.size() == 0) continue;
    if (norm == GradientNorm::kPerResponse) {
      const double n = B.cwiseAbs().maxCoeff();
      if (n > 0) note((A - B).cwiseAbs().maxCoeff() / n, name);
      continue;
    }
    for (Eigen::Index i = 0; i < B.rows(); ++i) {
      const double n = B.row(i).cwiseAbs().maxCoeff();
      if (n > 0)
        note((A.row(i) - B.row(i)).cwiseAbs().maxCoeff() / n, name + "[" + std::to_string(i) + "]");
    }
  }
  return d;
}

GradientCheckResult check_gradients(const Study& cs, const Vec& p,
                                    const std::vector<ResponseSensitivity>& gradients,
                                    const GradientCheckOptions& o) {
  if (!cs.design) throw SetupError("design", "a gradient check needs design variables");
  return check_gradients(*cs.design, p, gradients, o, [&](const Vec& x, SensitivityCounts& counts) {
    return simulate_responses(cs, x, counts);
  });
}

GradientCheckResult check_gradients(const Design& d, const Vec& p,
                                    const std::vector<ResponseSensitivity>& gradients,
                                    const GradientCheckOptions& o,
                                    const ResponseSimulator& simulate) {
  if (auto msg = o.validate(); !msg.empty()) throw Error("gradient check option " + msg);
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
  signal_point("gradient-check");
  try {
    plus = simulate(p + res.step, counts);
    minus = simulate(p - res.step, counts);
  } catch (const NumericalFailure& e) {
    res.ok = false;
    res.interrupted = interrupted() != 0;  // not a failure of the check: it did not finish
    res.message = e.what();
  }
  res.simulations = counts.simulations;
  if (!res.ok) return res;
  const Vec sd = scale.cwiseProduct(res.direction);
  // `gradients` may be any subset of the case's responses (optimize checks the objective and the
  // constraints only): the perturbed runs' responses are matched by name, not by position
  auto by_name = [](const std::vector<ResponseSensitivity>& all,
                    const std::string& name) -> const ResponseSensitivity* {
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
    if (!gp || !gm || gp->values.size() != g.values.size() ||
        gm->values.size() != g.values.size()) {
      res.ok = false;
      res.message =
          "response '" + g.name + "' changed its number of steps under the check's perturbation";
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

RunStatus GradientCheckResult::status() const {
  if (interrupted) return RunStatus::kInterrupted;
  return ok ? RunStatus::kComplete : RunStatus::kFailed;
}

std::string GradientCheckResult::report() const {
  char b[256];
  std::snprintf(b, sizeof b,
                "gradient check (central differences along a random direction, %ld simulations): "
                "%s, worst relative "
                "disagreement %.2e",
                simulations, run_status_name(status()), worst);
  std::string r = b;
  if (!ok) return r + "\n  " + message;
  for (const auto& e : entries) {
    std::snprintf(b, sizeof b, "\n  %-24s fd %+.6e  method %+.6e  relative disagreement %.2e",
                  e.response.c_str(), e.finite_difference, e.method, e.relative_error);
    r += b;
  }
  return r;
}

}  // namespace lsmbs
