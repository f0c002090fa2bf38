#include "lsmbs/optimization/kkt.hpp"

#include <Eigen/Dense>
#include <cmath>

namespace lsmbs {

nlohmann::json KktReport::to_json() const {
  return {{"active_constraints", active_constraints},
          {"free_variables", free_variables},
          {"at_lower_bound", at_lower},
          {"at_upper_bound", at_upper},
          {"multipliers", multipliers},
          {"stationarity", stationarity},
          {"bound_sign_violation", bound_sign_violation}};
}

KktReport kkt_report(const DesignProblem& prob, const Evaluation& e, double tol_active,
                     double tol_bound) {
  KktReport r;
  const Study& cs = prob.study();
  const Vec lo = cs.design->lower(), range = cs.design->upper() - cs.design->lower();
  const int n = static_cast<int>(e.p.size());
  const double fs = std::max(std::abs(e.objective), 1e-300);
  const Vec gf = e.objective_gradient.cwiseProduct(range) / fs;  // scaled ∇f
  auto scale = [&](size_t j) { return j < e.scale.size() ? e.scale[j] : std::abs(e.upper[j]); };
  std::vector<int> act;
  for (size_t j = 0; j < e.constraints.size(); ++j)
    if (std::abs(e.constraints[j] - e.upper[j]) <= tol_active * scale(j))
      act.push_back(static_cast<int>(j));
  r.active_constraints = static_cast<int>(act.size());
  Mat G(n, act.size());  // scaled ∇g_j as columns
  for (size_t k = 0; k < act.size(); ++k)
    G.col(k) = e.constraint_gradient.row(act[k]).transpose().cwiseProduct(range) /
               scale(static_cast<size_t>(act[k]));
  std::vector<int> free, lower, upper;
  for (int i = 0; i < n; ++i) {
    const double x = (e.p[i] - lo[i]) / range[i];
    if (x <= tol_bound)
      lower.push_back(i);
    else if (x >= 1 - tol_bound)
      upper.push_back(i);
    else
      free.push_back(i);
  }
  r.free_variables = static_cast<int>(free.size()), r.at_lower = static_cast<int>(lower.size()),
  r.at_upper = static_cast<int>(upper.size());
  Vec lambda = Vec::Zero(act.size());
  if (!act.empty() && !free.empty()) {  // least squares on the free rows, then clip at zero
    Mat A(free.size(), act.size());
    Vec b(free.size());
    for (size_t i = 0; i < free.size(); ++i) A.row(i) = G.row(free[i]), b[i] = -gf[free[i]];
    lambda = A.colPivHouseholderQr().solve(b).cwiseMax(0.0);
  }
  r.multipliers.assign(lambda.data(), lambda.data() + lambda.size());
  const Vec grad_l = gf + G * lambda;
  const double norm = std::max(gf.cwiseAbs().maxCoeff(), 1e-300);
  for (int i : free) r.stationarity = std::max(r.stationarity, std::abs(grad_l[i]) / norm);
  for (int i : lower)
    r.bound_sign_violation = std::max(r.bound_sign_violation, std::max(0.0, -grad_l[i]) / norm);
  for (int i : upper)
    r.bound_sign_violation = std::max(r.bound_sign_violation, std::max(0.0, grad_l[i]) / norm);
  return r;
}

}  // namespace lsmbs
