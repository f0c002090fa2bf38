#include "lsmbs/integrators/static_solver.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "lsmbs/integrators/generalized_alpha.hpp"
#include "lsmbs/linalg/sparse_lu.hpp"
#include "lsmbs/mbs/linear_solver_setup.hpp"

namespace lsmbs {

namespace {
// how far from the start, in model sizes, a static iterate may go before it counts as running away
constexpr double kRunaway = 1e6;
}  // namespace

std::string StaticOptions::validate() const {
  if (!std::isfinite(t)) return "t: expected a finite time";
  if (!(tol_r > 0)) return "tol_r: expected a positive tolerance";
  if (!(tol_phi > 0)) return "tol_phi: expected a positive tolerance";
  if (max_iter < 0) return "max_iter: expected a non-negative count";
  if (!(k >= 0)) return "k: expected a non-negative value (0 = automatic)";
  return {};
}

StaticResult solve_static(const Model& model, const ModelParams& p, State& s,
                          const StaticOptions& o) {
  StaticResult res;
  if (auto msg = o.validate(); !msg.empty()) {
    res.message = "invalid static option " + msg;
    return res;
  }
  const int nq = model.nq(), nc = model.nc();
  s.t = o.t;
  s.v.setZero(nq);
  s.a.setZero(nq);
  if (s.lambda.size() != nc) s.lambda.setZero(nc);
  SparseLU lu;
  analyze_model_matrix(lu, model, o.linear_solver, o.ordering);
  res.linear_solver = SparseLU::solver_name(lu.solver_used());
  std::vector<double> vals;
  const Coefficients cK{0, 0, 1};
  double k = o.k;
  if (!(k > 0)) {
    model.iteration_matrix(s, p, cK, 0, 0, vals);
    double sum = 0;
    int cnt = 0;
    for (int j = 0; j < nq; ++j)
      if (int i = model.pattern().find(j, j); i >= 0 && vals[i] != 0)
        sum += std::abs(vals[i]), ++cnt;
    k = cnt ? sum / cnt : 1.0;
  }
  Vec R, r_abs, dx, row_floor;
  const Vec q_start = s.q;
  auto norm = [&](const Vec& r) {
    return std::max(r.head(nq).lpNorm<Eigen::Infinity>(),
                    nc ? r.tail(nc).lpNorm<Eigen::Infinity>() : 0.0);
  };
  // The test of the dynamic Newton iteration, row by row (docs/methods.md, "Convergence test"):
  // |r_i| ≤ tol_r s_i + f_i, s_i the sum of the absolute force terms of row i, f_i its round-off
  // floor through the stiffness at the current iterate. One global scale (the largest s_i) let a
  // stiff element's rows hide the applied load elsewhere.
  auto rows_converged = [&] {
    for (int i = 0; i < nq; ++i)
      if (!(std::abs(R[i]) <= o.tol_r * r_abs[i] + row_floor[i])) return false;
    return true;
  };
  for (res.iterations = 0; res.iterations <= o.max_iter; ++res.iterations) {
    model.residual(s, p, k, 0.0, R, &r_abs);
    res.residual_norm = R.head(nq).lpNorm<Eigen::Infinity>();
    model.iteration_matrix(s, p, cK, k, 0.0, vals);
    row_round_off_floor(model.pattern(), vals, s.q, model.length_scale(), nq, row_floor);
    const double pn = nc ? R.tail(nc).lpNorm<Eigen::Infinity>() / k : 0.0;
    // a body that nothing holds runs away along its rigid motion (the stiffness is singular
    // up to round-off), where the row floors grow with |q| until they pass: refuse that state
    const double moved = (s.q - q_start).lpNorm<Eigen::Infinity>();
    if (!(moved <= kRunaway * model.length_scale())) {
      char b[200];
      std::snprintf(b, sizeof b,
                    "the state ran away (%.3e m from the start, %.0e times the model's size): a "
                    "body or a rigid motion is not held; a static equilibrium needs every body "
                    "held by joints or springs",
                    moved, kRunaway);
      res.message = b;
      return res;
    }
    if (rows_converged() && pn <= o.tol_phi * model.length_scale()) {
      // a reflected element is stress-free: a spurious equilibrium, not the structure's
      if (const auto inv = model.most_compressed_element(s.q, p); inv.inverted()) {
        res.message = "static Newton converged to a state with an inverted element, " +
                      inv.describe() +
                      ": a reflected St Venant–Kirchhoff element is stress-free, a spurious "
                      "equilibrium";
        return res;
      }
      res.ok = true;
      return res;
    }
    if (res.iterations == o.max_iter) break;
    if (auto st = lu.factor(vals); !st.ok()) {
      res.message = "singular stiffness matrix: " + model.describe_unknown(lu.singular_column()) +
                    " is not held by any constraint";
      return res;
    }
    dx = -R;
    lu.solve(dx);
    // backtracking on ‖R‖
    const double r0 = norm(R);
    double step = 1;
    const Vec q0 = s.q, l0 = s.lambda;
    for (int ls = 0; ls < 10; ++ls) {
      s.q = q0 + step * dx.head(nq);
      s.lambda = l0 + step * dx.tail(nc);
      model.residual(s, p, k, 0.0, R);
      if (R.allFinite() && norm(R) < r0) break;
      step *= 0.5;
    }
  }
  char b[120];
  std::snprintf(b, sizeof b, "static Newton did not converge (‖r‖∞ = %.3e N)", res.residual_norm);
  res.message = b;
  return res;
}

RunStatus StaticResult::status() const { return ok ? RunStatus::kComplete : RunStatus::kFailed; }

std::string StaticResult::report() const {
  char b[160];
  std::snprintf(b, sizeof b, "static equilibrium: %s: %d Newton iterations, residual norm %.3e",
                run_status_name(status()), iterations, residual_norm);
  return message.empty() ? std::string(b) : std::string(b) + "\n  " + message;
}

}  // namespace lsmbs
