#include "lsmbs/integrators/initial_state.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace lsmbs {

namespace {
std::string speed_text(double v) {  // 7.8e-05, 0.68, 11.1: small violations stay visible
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}
}  // namespace

namespace {

std::string short_number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

// [ I  Φ_qᵀ ; Φ_q  0 ] on the model pattern.
Status factor_projection(const Model& model, const ModelParams& p, const State& s, SparseLU& lu,
                         std::vector<double>& vals) {
  model.iteration_matrix(s, p, Coefficients{0, 0, 0}, 1.0, 0.0, vals);
  for (int i = 0; i < model.nq(); ++i) model.assembler().add_diagonal(vals, i, 1.0);
  lu.reset_pivoting();
  return lu.factor(vals);
}

// Metric of the velocity projection: 1 for translations, L² for rigid-body angles (an angular
// rate weighs as the speed it gives a point at the model's length scale L; likewise the rates
// of a spatial body's unit vectors).
Vec velocity_weights(const Model& model) {
  Vec w = Vec::Ones(model.nq());
  const double L = model.length_scale();
  for (const auto& b : model.rigid_bodies()) w[b.dof0 + 2] = L * L;
  // spatial bodies: the rates of their unit vectors [1/s], as the speeds L ė they give
  for (const auto& b : model.spatial_bodies()) w.segment<9>(b.dof0 + 3).setConstant(L * L);
  return w;
}

// [ W  Φ_qᵀ ; Φ_q  −δI ] on the model pattern. Held unknowns get an identity row and no coupling
// to the constraints, so their correction is zero; δ > 0 keeps the matrix regular when the
// constraints restricted to the other unknowns are dependent (velocities given for every body).
Status factor_velocity_projection(const Model& model, const ModelParams& p, const State& s,
                                  SparseLU& lu, std::vector<double>& vals, const Vec& w,
                                  const std::vector<char>* held, double delta) {
  model.iteration_matrix(s, p, Coefficients{0, 0, 0}, 1.0, 0.0, vals);
  const int nq = model.nq(), n = model.n();
  const auto& pat = model.pattern();
  if (held)
    for (int j = 0; j < n; ++j)
      for (int k = pat.col_ptr[j]; k < pat.col_ptr[j + 1]; ++k) {
        const int i = pat.row_ind[k];
        if ((j < nq && i >= nq && (*held)[j]) || (j >= nq && i < nq && (*held)[i])) vals[k] = 0;
      }
  for (int i = 0; i < nq; ++i)
    model.assembler().add_diagonal(vals, i, held && (*held)[i] ? 1.0 : w[i]);
  for (int i = nq; i < n && delta > 0; ++i) model.assembler().add_diagonal(vals, i, -delta);
  lu.reset_pivoting();
  return lu.factor(vals);
}

}  // namespace

Status project_initial_state(const Model& model, const ModelParams& p, State& s, SparseLU& lu,
                             double tol, ProjectionReport* rep, const std::vector<char>* held) {
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
    if (!phi.allFinite())
      return Status::Fail(Status::Code::kNonFinite, "initial position projection diverged");
  }
  if (phi.lpNorm<Eigen::Infinity>() > tol)
    return Status::Fail(Status::Code::kNotConverged,
                        "cannot assemble the initial configuration: ‖Φ‖ = " +
                            std::to_string(phi.lpNorm<Eigen::Infinity>()) +
                            " after 50 projections");
  if (rep) {
    rep->phi_after = phi.lpNorm<Eigen::Infinity>();
    rep->iterations = it;
  }
  // Velocity: Φ_q q̇ + Φ_t = 0 with the smallest change ‖Δq̇‖_W of the unknowns not held.
  model.constraint_time_terms(s.t, s.q, s.v, p, phi_t, gamma);
  const SpMat J = model.constraint_jacobian(s.t, s.q, p);
  const Vec w = velocity_weights(model);
  Vec vc = J * s.v + phi_t;
  if (rep) rep->vel_before = vc.lpNorm<Eigen::Infinity>();
  bool any_held = false;
  if (held)
    for (int i = 0; i < nq; ++i) any_held = any_held || (*held)[i];
  if (any_held) {
    // Row i's violation as a speed: |vc_i| over the W⁻¹-norm of its row (the W-distance of q̇ from
    // the row's hyperplane), so that rows in m/s and in rad/s compare.
    Vec row_norm = Vec::Zero(nc);
    for (int j = 0; j < J.outerSize(); ++j)
      for (SpMat::InnerIterator e(J, j); e; ++e) row_norm[e.row()] += e.value() * e.value() / w[j];
    row_norm = row_norm.cwiseSqrt();
    double speed = 0, min_row = 1e300;  // velocity scale of the problem
    for (int j = 0; j < nq; ++j) speed = std::max(speed, std::abs(s.v[j]) * std::sqrt(w[j]));
    for (int i = 0; i < nc; ++i)
      if (row_norm[i] > 0) {
        speed = std::max(speed, std::abs(phi_t[i]) / row_norm[i]);
        min_row = std::min(min_row, row_norm[i] * row_norm[i]);
      }
    auto violation = [&](const Vec& r) {
      double m = 0;
      for (int i = 0; i < nc; ++i)
        if (row_norm[i] > 0) m = std::max(m, std::abs(r[i]) / row_norm[i]);
      return m;
    };
    const Vec v_given = s.v;
    // Iterated regularized projection: each pass removes all but δ/(σ² + δ) of the residual along
    // every direction the free unknowns can reach (σ² the eigenvalues of J_F W⁻¹ J_Fᵀ).
    const double delta = 1e-10 * min_row;
    if (auto st = factor_velocity_projection(model, p, s, lu, vals, w, held, delta); !st.ok())
      return st;
    double v_now = violation(vc);
    for (int pass = 0; pass < 10 && v_now > 1e-15 * speed; ++pass) {
      rhs.head(nq).setZero();
      rhs.tail(nc) = -vc;
      lu.solve(rhs);
      const Vec v_old = s.v;
      s.v += rhs.head(nq);
      vc = J * s.v + phi_t;
      const double v_next = violation(vc);
      if (!(v_next < v_now)) {  // round-off reached
        if (!(v_next <= v_now)) s.v = v_old, vc = J * s.v + phi_t;
        break;
      }
      v_now = v_next;
    }
    // Given velocities that contradict the constraints beyond round-off of the data: reported.
    if (violation(vc) > 1e-9 * speed) {
      std::string msg;
      std::vector<char> in_conflict(nq, 0);
      for (int i = 0; i < nc; ++i) {
        if (!(row_norm[i] > 0) || !(std::abs(vc[i]) / row_norm[i] > 1e-9 * speed)) continue;
        if (rep)
          rep->conflicting_rows.push_back(i),
              rep->conflict_speed.push_back(std::abs(vc[i]) / row_norm[i]);
        if (msg.size() < 400)
          msg += (msg.empty() ? "" : "; ") + model.describe_unknown(nq + i) + " violated by " +
                 speed_text(std::abs(vc[i]) / row_norm[i]) + " m/s";
      }
      for (int j = 0; j < J.outerSize(); ++j)
        for (SpMat::InnerIterator e(J, j); e; ++e)
          if ((*held)[j] && e.value() != 0 &&
              std::abs(vc[e.row()]) / row_norm[e.row()] > 1e-9 * speed)
            in_conflict[j] = 1;
      if (rep)
        for (int j = 0; j < nq; ++j)
          if (in_conflict[j]) rep->conflicting_held.push_back(j);
      // what the drivers demand at t0 (Φ = coordinate − s(t): Φ_t = −ṡ): a conflict on a joint
      // is often a driver's law whose speed at t0 is not the one the given velocities assume
      std::string drivers;
      for (int i = 0; i < nc; ++i)
        if (phi_t[i] != 0 && drivers.size() < 300)
          drivers += (drivers.empty() ? "" : ", ") + model.describe_unknown(nq + i) +
                     " at ds/dt = " + short_number(-phi_t[i]);
      s.v = v_given;
      lu.reset_pivoting();
      return Status::Fail(
          Status::Code::kNotConverged,
          "the given initial velocities contradict the constraints (" + msg +
              "; speeds in the metric where an angular rate counts times the length scale " +
              std::to_string(model.length_scale()) + " m)" +
              (drivers.empty()
                   ? std::string("; no driver moves at t = ") + short_number(s.t)
                   : "; at t = " + short_number(s.t) + " the laws move their drivers: " + drivers));
    }
  } else if (vc.lpNorm<Eigen::Infinity>() > 0) {
    if (auto st = factor_velocity_projection(model, p, s, lu, vals, w, nullptr, 0.0); !st.ok())
      return st;
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

Status consistent_accelerations(const Model& model, const ModelParams& p, double k, State& s,
                                SparseLU& lu) {
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
    return Status::Fail(st.code, "consistent initial accelerations: " + st.message + " — " +
                                     model.describe_unknown(lu.singular_column()) +
                                     model.why_no_pivot(lu.singular_column(), p));
  Vec rhs(model.n());
  rhs.head(nq) = -R.head(nq);
  rhs.tail(nc) = -k * gamma;
  lu.solve(rhs);
  if (!rhs.allFinite())
    return Status::Fail(Status::Code::kNonFinite,
                        "consistent initial accelerations are not finite");
  s.a = rhs.head(nq);
  s.lambda = rhs.tail(nc);
  return Status::Ok();  // the factorization of the start system stays in `lu` for the caller
}

}  // namespace lsmbs
