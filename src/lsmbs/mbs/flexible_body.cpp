#include "lsmbs/mbs/flexible_body.hpp"

namespace lsmbs {

double FlexibleBody::mass(const ModelParams& p) const {
  double m = 0;
  const Vec& mu = p.fields[field];
  for (size_t e = 0; e < elements.size(); ++e) m += mu[e] * elements[e].area();
  return m * p.scalars[rho_param] * p.scalars[thickness_param];
}

QuadForce::QuadForce(const FlexibleBody* body, int element) : body_(body), e_(element) {
  const auto& q = body->mesh.quads[element];
  for (int i = 0; i < 4; ++i) {
    dofs_[2 * i] = body->node_dof(q[i]);
    dofs_[2 * i + 1] = body->node_dof(q[i]) + 1;
  }
}

std::string QuadForce::describe() const {
  return "body '" + body_->name + "', element " + std::to_string(e_);
}

void QuadForce::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                         const Coefficients* c, LocalMat* S) const {
  const QuadElement& el = body_->elements[e_];
  const double mu = p.fields[body_->field][e_];
  const double t = p.scalars[body_->thickness_param];
  const double rho = mu * p.scalars[body_->rho_param];
  const double E = mu * p.scalars[body_->E_param], nu = p.scalars[body_->nu_param];
  QuadElement::Vec8 x = s.q.head<8>(), f;
  QuadElement::Mat8 K;
  const bool want_K = S && c->cq != 0;
  el.internal_force(x, E, nu, t, f, want_K ? &K : nullptr);
  const auto& M0 = el.unit_mass();
  const auto& N0 = el.shape_integrals();
  const double mt = rho * t;
  for (int i = 0; i < 4; ++i) {
    double ax = 0, ay = 0;
    for (int j = 0; j < 4; ++j) {
      ax += M0(i, j) * s.a[2 * j];
      ay += M0(i, j) * s.a[2 * j + 1];
    }
    r[2 * i] += mt * ax + f[2 * i] - mt * N0[i] * p.gravity.x();
    r[2 * i + 1] += mt * ay + f[2 * i + 1] - mt * N0[i] * p.gravity.y();
  }
  if (!S) return;
  if (want_K) S->topLeftCorner<8, 8>() += c->cq * K;
  if (c->ca != 0)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        (*S)(2 * i, 2 * j) += c->ca * mt * M0(i, j);
        (*S)(2 * i + 1, 2 * j + 1) += c->ca * mt * M0(i, j);
      }
}

void QuadForce::param_derivative(const LocalState& s, const ModelParams& p, int j,
                                 LocalVec& dr) const {
  // r = μ ρ0 t (M0 q̈ − N0 g) + f_int(μ E0, ν, t), f_int linear in E and t.
  if (!uses_parameter(j)) return;
  const QuadElement& el = body_->elements[e_];
  const double mu = p.fields[body_->field][e_];
  const double t = p.scalars[body_->thickness_param], rho0 = p.scalars[body_->rho_param];
  const double E0 = p.scalars[body_->E_param], nu = p.scalars[body_->nu_param];
  const QuadElement::Vec8 x = s.q.head<8>();
  QuadElement::Vec8 df = QuadElement::Vec8::Zero(), f;
  double dmt = 0;  // ∂(μ ρ0 t)/∂p_j
  if (j == body_->E_param) {
    el.internal_force(x, mu, nu, t, f, nullptr);  // ∂f_int/∂E0 = f_int at E = μ
    df += f;
  }
  if (j == body_->nu_param) {
    el.internal_force_nu_derivative(x, mu * E0, nu, t, f);
    df += f;
  }
  if (j == body_->thickness_param) {
    el.internal_force(x, mu * E0, nu, 1.0, f, nullptr);  // ∂f_int/∂t = f_int at t = 1
    df += f;
    dmt += mu * rho0;
  }
  if (j == body_->rho_param) dmt += mu * t;
  const auto& M0 = el.unit_mass();
  const auto& N0 = el.shape_integrals();
  for (int i = 0; i < 4; ++i) {
    double ax = 0, ay = 0;
    for (int k = 0; k < 4; ++k) {
      ax += M0(i, k) * s.a[2 * k];
      ay += M0(i, k) * s.a[2 * k + 1];
    }
    dr[2 * i] += dmt * (ax - N0[i] * p.gravity.x()) + df[2 * i];
    dr[2 * i + 1] += dmt * (ay - N0[i] * p.gravity.y()) + df[2 * i + 1];
  }
}

void QuadForce::mass_damping(const LocalState&, const ModelParams& p, LocalMat& M,
                             LocalMat& C) const {
  const double mt =
      p.fields[body_->field][e_] * p.scalars[body_->rho_param] * p.scalars[body_->thickness_param];
  const auto& M0 = body_->elements[e_].unit_mass();
  M.setZero(8, 8);
  C.setZero(8, 8);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) M(2 * i, 2 * j) = M(2 * i + 1, 2 * j + 1) = mt * M0(i, j);
}

}  // namespace lsmbs
