#include "lsmbs/mbs/flexible_body.hpp"

namespace lsmbs {

double FlexibleBody::mass(const ModelParams& p) const {
  double m = 0;
  const Vec& mu = p.fields[field];
  for (size_t e = 0; e < elements.size(); ++e) m += mu[e] * elements[e]->area();
  return m * p.scalars[rho_param] * p.scalars[thickness_param];
}

int FlexibleBody::element_coordinates(int e, const Vec& q, double* x) const {
  const Cell& c = mesh.cells[static_cast<size_t>(e)];
  for (int k = 0; k < c.size(); ++k) {
    const int d = node_dof(c[k]);
    x[2 * k] = q[d];
    x[2 * k + 1] = q[d + 1];
  }
  return 2 * c.size();
}

PlaneForce::PlaneForce(const FlexibleBody* body, int element) : body_(body), e_(element) {
  const Cell& c = body->mesh.cells[static_cast<size_t>(element)];
  n_ = static_cast<size_t>(2 * c.size());
  for (int i = 0; i < c.size(); ++i) {
    dofs_[2 * i] = body->node_dof(c[i]);
    dofs_[2 * i + 1] = body->node_dof(c[i]) + 1;
  }
}

std::string PlaneForce::describe() const {
  return "body '" + body_->name + "', element " + std::to_string(e_);
}

// r = μ ρ0 t (M0 q̈ − N0 g) + f_int(μ E0, ν, t) with M0 = ∫ N_I N_J dA, N0 = ∫ N_I dA (eq. 3)
void PlaneForce::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                          const Coefficients* c, LocalMat* S) const {
  const PlaneElement& el = *body_->elements[static_cast<size_t>(e_)];
  const int n = el.num_nodes(), nd = 2 * n;
  const double mu = p.fields[body_->field][e_];
  const double t = p.scalars[body_->thickness_param];
  const double rho = mu * p.scalars[body_->rho_param];
  const double E = mu * p.scalars[body_->E_param], nu = p.scalars[body_->nu_param];
  double f[kMaxLocalDofs], K[kMaxLocalDofs * kMaxLocalDofs];
  const bool want_K = S && c->cq != 0;
  el.internal_force(s.q.data(), E, nu, t, f, want_K ? K : nullptr);
  const auto M0 = el.unit_mass();
  const auto N0 = el.shape_integrals();
  const double mt = rho * t;
  for (int i = 0; i < n; ++i) {
    double ax = 0, ay = 0;
    for (int j = 0; j < n; ++j) {
      ax += M0(i, j) * s.a[2 * j];
      ay += M0(i, j) * s.a[2 * j + 1];
    }
    r[2 * i] += mt * ax + f[2 * i] - mt * N0[i] * p.gravity.x();
    r[2 * i + 1] += mt * ay + f[2 * i + 1] - mt * N0[i] * p.gravity.y();
  }
  if (!S) return;
  if (want_K) S->topLeftCorner(nd, nd) += c->cq * Eigen::Map<const Eigen::MatrixXd>(K, nd, nd);
  if (c->ca != 0)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        (*S)(2 * i, 2 * j) += c->ca * mt * M0(i, j);
        (*S)(2 * i + 1, 2 * j + 1) += c->ca * mt * M0(i, j);
      }
}

void PlaneForce::param_derivative(const LocalState& s, const ModelParams& p, int j,
                                  LocalVec& dr) const {
  // r = μ ρ0 t (M0 q̈ − N0 g) + f_int(μ E0, ν, t), f_int linear in E and t.
  if (!uses_parameter(j)) return;
  const PlaneElement& el = *body_->elements[static_cast<size_t>(e_)];
  const int n = el.num_nodes(), nd = 2 * n;
  const double mu = p.fields[body_->field][e_];
  const double t = p.scalars[body_->thickness_param], rho0 = p.scalars[body_->rho_param];
  const double E0 = p.scalars[body_->E_param], nu = p.scalars[body_->nu_param];
  const double* x = s.q.data();
  double df[kMaxLocalDofs] = {}, f[kMaxLocalDofs];
  double dmt = 0;  // ∂(μ ρ0 t)/∂p_j
  auto add = [&] {
    for (int k = 0; k < nd; ++k) df[k] += f[k];
  };
  if (j == body_->E_param) {
    el.internal_force(x, mu, nu, t, f, nullptr);  // ∂f_int/∂E0 = f_int at E = μ
    add();
  }
  if (j == body_->nu_param) {
    el.internal_force_nu_derivative(x, mu * E0, nu, t, f);
    add();
  }
  if (j == body_->thickness_param) {
    el.internal_force(x, mu * E0, nu, 1.0, f, nullptr);  // ∂f_int/∂t = f_int at t = 1
    add();
    dmt += mu * rho0;
  }
  if (j == body_->rho_param) dmt += mu * t;
  const auto M0 = el.unit_mass();
  const auto N0 = el.shape_integrals();
  for (int i = 0; i < n; ++i) {
    double ax = 0, ay = 0;
    for (int k = 0; k < n; ++k) {
      ax += M0(i, k) * s.a[2 * k];
      ay += M0(i, k) * s.a[2 * k + 1];
    }
    dr[2 * i] += dmt * (ax - N0[i] * p.gravity.x()) + df[2 * i];
    dr[2 * i + 1] += dmt * (ay - N0[i] * p.gravity.y()) + df[2 * i + 1];
  }
}

void PlaneForce::mass_damping(const LocalState&, const ModelParams& p, LocalMat& M,
                              LocalMat& C) const {
  const double mt =
      p.fields[body_->field][e_] * p.scalars[body_->rho_param] * p.scalars[body_->thickness_param];
  const auto M0 = body_->elements[static_cast<size_t>(e_)]->unit_mass();
  const auto n = M0.rows(), nd = 2 * n;
  M.setZero(nd, nd);
  C.setZero(nd, nd);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) M(2 * i, 2 * j) = M(2 * i + 1, 2 * j + 1) = mt * M0(i, j);
}

void PlaneForce::field_derivative(const LocalState& s, const ModelParams& p, LocalVec& dr) const {
  LocalVec r = LocalVec::Zero(static_cast<Eigen::Index>(n_));
  evaluate(s, p, r, nullptr, nullptr);
  const double mu = p.fields[body_->field][e_];
  for (size_t i = 0; i < n_; ++i)
    dr[static_cast<Eigen::Index>(i)] += r[static_cast<Eigen::Index>(i)] / mu;
}

}  // namespace lsmbs
