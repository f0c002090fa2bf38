#include "lsmbs/integrators/initial_state.hpp"

#include <cmath>

namespace lsmbs {
namespace {

// [ I  Φ_qᵀ ; Φ_q  0 ] on the model pattern.
Status factor_projection(const Model& model, const ModelParams& p, const State& s, SparseLU& lu,
                         std::vector<double>& vals) {
  model.iteration_matrix(s, p, Coefficients{0, 0, 0}, 1.0, 0.0, vals);
  for (int i = 0; i < model.nq(); ++i) model.assembler().add_diagonal(vals, i, 1.0);
  lu.reset_pivoting();
  return lu.factor(vals);
}

}  // namespace

Status project_initial_state(const Model& model, const ModelParams& p, State& s, SparseLU& lu, double tol,
                             ProjectionReport* rep) {
  const int nq = model.nq(), nc = model.nc();
  if (nc == 0) return Status::Ok();
  std::vector<double> vals;
  Vec phi, rhs(model.n()), phi_t, gamma;
  model.constraints(s.t, s.q, p, phi);
  if (rep) rep->phi_before = phi.lpNorm<Eigen::Infinity>();
  int it = 0;
  for (; it < 50 && phi.lpNorm<Eigen::Infinity>() > tol; ++it) {
    if (auto st = factor_projection(model, p, s, lu, vals); !st.ok()) return st;
    rhs.head(nq).setZero();
    rhs.tail(nc) = -phi;
    lu.solve(rhs);
    s.q += rhs.head(nq);
    model.constraints(s.t, s.q, p, phi);
    if (!phi.allFinite()) return Status::Fail(Status::Code::kNonFinite, "initial position projection diverged");
  }
  if (phi.lpNorm<Eigen::Infinity>() > tol)
    return Status::Fail(Status::Code::kNotConverged,
                        "cannot assemble the initial configuration: ‖Φ‖ = " +
                            std::to_string(phi.lpNorm<Eigen::Infinity>()) + " after 50 projections");
  if (rep) {
    rep->phi_after = phi.lpNorm<Eigen::Infinity>();
    rep->iterations = it;
  }
  // Velocity: Φ_q q̇ + Φ_t = 0.
  model.constraint_time_terms(s.t, s.q, s.v, p, phi_t, gamma);
  const SpMat J = model.constraint_jacobian(s.t, s.q, p);
  Vec vc = J * s.v + phi_t;
  if (rep) rep->vel_before = vc.lpNorm<Eigen::Infinity>();
  if (vc.lpNorm<Eigen::Infinity>() > 0) {
    if (auto st = factor_projection(model, p, s, lu, vals); !st.ok()) return st;
    rhs.head(nq).setZero();
    rhs.tail(nc) = -vc;
    lu.solve(rhs);
    s.v += rhs.head(nq);
    vc = J * s.v + phi_t;
  }
  if (rep) rep->vel_after = vc.lpNorm<Eigen::Infinity>();
  lu.reset_pivoting();
  return Status::Ok();
}

Status consistent_accelerations(const Model& model, const ModelParams& p, double k, State& s, SparseLU& lu) {
  const int nq = model.nq(), nc = model.nc();
  State s0 = s;
  s0.a.setZero(nq);
  s0.lambda.setZero(nc);
  Vec R;
  model.residual(s0, p, k, 0.0, R);
  Vec phi_t, gamma;
  model.constraint_time_terms(s.t, s.q, s.v, p, phi_t, gamma);
  std::vector<double> vals;
  model.iteration_matrix(s0, p, Coefficients{1, 0, 0}, k, 0.0, vals);
  lu.reset_pivoting();
  if (auto st = lu.factor(vals); !st.ok())
    return Status::Fail(st.code, "consistent initial accelerations: " + st.message +
                                     " — " + model.describe_unknown(lu.singular_column()) +
                                     " has no mass and is not fixed by a constraint");
  Vec rhs(model.n());
  rhs.head(nq) = -R.head(nq);
  rhs.tail(nc) = -k * gamma;
  lu.solve(rhs);
  if (!rhs.allFinite()) return Status::Fail(Status::Code::kNonFinite, "consistent initial accelerations are not finite");
  s.a = rhs.head(nq);
  s.lambda = rhs.tail(nc);
  return Status::Ok();  // the factorization of the start system stays in `lu` for the caller
}

}  // namespace lsmbs
