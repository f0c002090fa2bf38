#include "lsmbs/optimization/kkt.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace lsmbs {

nlohmann::json KktReport::to_json() const {
  return {{"active_constraints", active_constraints},
          {"free_variables", free_variables},
          {"at_lower_bound", at_lower},
          {"at_upper_bound", at_upper},
          {"multipliers", multipliers},
          {"stationarity", stationarity},
          {"bound_sign_violation", bound_sign_violation},
          {"complementarity", complementarity},
          {"tolerance", tolerance},
          {"verdict", satisfied() ? "satisfied" : "not satisfied"}};
}

Vec nonnegative_least_squares(const Mat& A_in, const Vec& b) {
  const Eigen::Index n = A_in.cols();
  Vec x = Vec::Zero(n);
  if (n == 0) return x;
  // columns scaled to unit norm (x_j scaled back at the end): the test of which column enters is
  // then independent of the columns' units (the KKT report's objective may be scaled by a tiny |f|)
  Vec col_norm(n);
  Mat A = A_in;
  for (Eigen::Index j = 0; j < n; ++j) {
    col_norm[j] = A.col(j).norm();
    if (col_norm[j] > 0) A.col(j) /= col_norm[j];
  }
  std::vector<char> passive(static_cast<size_t>(n), 0);
  const double tol = 10 * std::numeric_limits<double>::epsilon() * std::max(1.0, b.norm()) *
                     static_cast<double>(std::max(A.rows(), n));
  // the least-squares solution on the passive set (zero elsewhere)
  auto solve_passive = [&] {
    std::vector<Eigen::Index> idx;
    for (Eigen::Index j = 0; j < n; ++j)
      if (passive[j]) idx.push_back(j);
    Mat Ap(A.rows(), static_cast<Eigen::Index>(idx.size()));
    for (size_t k = 0; k < idx.size(); ++k) Ap.col(static_cast<Eigen::Index>(k)) = A.col(idx[k]);
    const Vec zp = Ap.colPivHouseholderQr().solve(b);
    Vec z = Vec::Zero(n);
    for (size_t k = 0; k < idx.size(); ++k) z[idx[k]] = zp[static_cast<Eigen::Index>(k)];
    return z;
  };
  for (int outer = 0; outer < 3 * n + 10; ++outer) {
    const Vec w = A.transpose() * (b - A * x);  // the negative gradient of ½‖Ax − b‖²
    Eigen::Index t = -1;
    for (Eigen::Index j = 0; j < n; ++j)
      if (!passive[j] && w[j] > tol && (t < 0 || w[j] > w[t])) t = j;
    if (t < 0) break;  // the KKT conditions of the NNLS problem hold
    passive[t] = 1;
    for (int inner = 0; inner < 3 * n + 10; ++inner) {
      const Vec z = solve_passive();
      bool feasible = true;
      for (Eigen::Index j = 0; j < n; ++j) feasible &= !passive[j] || z[j] > 0;
      if (feasible) {
        x = z;
        break;
      }
      double alpha = 1;  // the longest step from x towards z that keeps x ≥ 0
      for (Eigen::Index j = 0; j < n; ++j)
        if (passive[j] && z[j] <= 0) alpha = std::min(alpha, x[j] / (x[j] - z[j]));
      x += alpha * (z - x);
      for (Eigen::Index j = 0; j < n; ++j)
        if (passive[j] && x[j] <= tol) passive[j] = 0, x[j] = 0;
    }
  }
  for (Eigen::Index j = 0; j < n; ++j) x[j] = col_norm[j] > 0 ? x[j] / col_norm[j] : 0.0;
  return x;
}

KktReport kkt_report(const DesignProblem& prob, const Evaluation& e, double tol_active,
                     double tol_bound, double objective_scale) {
  KktReport r;
  r.tolerance = prob.spec().kkt_tolerance;
  const Study& cs = prob.study();
  const Vec lo = cs.design->lower(), range = cs.design->upper() - cs.design->lower();
  const Eigen::Index n = e.p.size();
  const Eigen::Index m = static_cast<Eigen::Index>(e.constraints.size());
  const double fs = std::max(objective_scale > 0 ? objective_scale : std::abs(e.objective), 1e-300);
  const Vec gf = e.objective_gradient.cwiseProduct(range) / fs;  // scaled ∇f
  const double norm = std::max(gf.cwiseAbs().maxCoeff(), 1e-300);
  auto scale = [&](Eigen::Index j) {
    const auto k = static_cast<size_t>(j);
    return k < e.scale.size() ? e.scale[k] : std::abs(e.upper[k]);
  };
  Mat G(n, m);   // scaled ∇g_j as columns
  Vec slack(m);  // scaled (g_j − ū_j): ≤ 0 when feasible
  for (Eigen::Index j = 0; j < m; ++j) {
    G.col(j) = e.constraint_gradient.row(j).transpose().cwiseProduct(range) / scale(j);
    slack[j] = (e.constraints[static_cast<size_t>(j)] - e.upper[static_cast<size_t>(j)]) / scale(j);
    if (std::abs(slack[j]) <= tol_active) ++r.active_constraints;
  }
  Vec x(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    x[i] = (e.p[i] - lo[i]) / range[i];
    if (x[i] <= tol_bound)
      ++r.at_lower;
    else if (x[i] >= 1 - tol_bound)
      ++r.at_upper;
    else
      ++r.free_variables;
  }
  // multipliers: stationarity on the rows of the variables not held at a bound (a bound's own
  // multiplier takes up its row), complementarity rows λ_j s_j
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < n; ++i) {
    const bool held_low = x[i] <= tol_bound && gf[i] > 0;
    const bool held_up = x[i] >= 1 - tol_bound && gf[i] < 0;
    if (!held_low && !held_up) rows.push_back(i);
  }
  Vec lambda = Vec::Zero(m);
  if (m > 0) {
    const Eigen::Index nr = static_cast<Eigen::Index>(rows.size());
    Mat A = Mat::Zero(nr + m, m);
    Vec b = Vec::Zero(nr + m);
    for (Eigen::Index k = 0; k < nr; ++k)
      A.row(k) = G.row(rows[k]) / norm, b[k] = -gf[rows[k]] / norm;
    for (Eigen::Index j = 0; j < m; ++j) A(nr + j, j) = std::abs(slack[j]) / norm;
    lambda = nonnegative_least_squares(A, b);
  }
  r.multipliers.assign(lambda.data(), lambda.data() + lambda.size());
  const Vec grad_l = (gf + G * lambda) / norm;
  for (Eigen::Index i = 0; i < n; ++i) {
    // projected gradient on [0, 1]: x − clamp(x − ∇L)
    const double projected = x[i] - std::clamp(x[i] - grad_l[i], 0.0, 1.0);
    r.stationarity = std::max(r.stationarity, std::abs(projected));
    if (x[i] <= tol_bound) r.bound_sign_violation = std::max(r.bound_sign_violation, -grad_l[i]);
    if (x[i] >= 1 - tol_bound) r.bound_sign_violation = std::max(r.bound_sign_violation, grad_l[i]);
  }
  for (Eigen::Index j = 0; j < m; ++j)
    r.complementarity = std::max(r.complementarity, lambda[j] * std::abs(slack[j]) / norm);
  return r;
}

}  // namespace lsmbs
