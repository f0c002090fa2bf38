#include "lsmbs/mbs/solid_body.hpp"

namespace lsmbs {

double SolidBody::mass(const ModelParams& p) const {
  double m = 0;
  const Vec& mu = p.fields[static_cast<size_t>(field)];
  for (size_t e = 0; e < elements.size(); ++e)
    m += mu[static_cast<Eigen::Index>(e)] * elements[e]->volume();
  return m * p.scalars[static_cast<size_t>(rho_param)];
}

int SolidBody::element_coordinates(int e, const Vec& q, double* x) const {
  const auto& c = mesh.cells[static_cast<size_t>(e)];
  for (size_t i = 0; i < c.size(); ++i)
    for (int k = 0; k < 3; ++k) x[3 * i + static_cast<size_t>(k)] = q[node_dof(c[i]) + k];
  return 3 * static_cast<int>(c.size());
}

double SolidBody::element_E(int e, const ModelParams& p) const {
  return p.fields[static_cast<size_t>(field)][e] * p.scalars[static_cast<size_t>(E_param)];
}

SolidForce::SolidForce(const SolidBody* body, int element) : body_(body), e_(element) {
  const auto& c = body->mesh.cells[static_cast<size_t>(element)];
  n_ = 3 * c.size();
  for (size_t i = 0; i < c.size(); ++i)
    for (int k = 0; k < 3; ++k) dofs_[3 * i + static_cast<size_t>(k)] = body->node_dof(c[i]) + k;
}

std::string SolidForce::describe() const {
  return "solid body '" + body_->name + "', element " + std::to_string(e_);
}

namespace {
// M0 q̈ per direction: the element's nodal inertia times its unit mass
void add_inertia(const SolidElement& el, const LocalState& s, double m, const Vec3& g, LocalVec& r,
                 double sign = 1) {
  const auto M0 = el.unit_mass();
  const auto N0 = el.shape_integrals();
  const int n = el.num_nodes();
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      double a = 0;
      for (int j = 0; j < n; ++j) a += M0(i, j) * s.a[3 * j + k];
      r[3 * i + k] += sign * m * (a - N0[i] * g[k]);
    }
}
}  // namespace

void SolidForce::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                          const Coefficients* c, LocalMat* S) const {
  const SolidElement& el = *body_->elements[static_cast<size_t>(e_)];
  const int nd = el.num_dofs();
  const double mu = p.fields[static_cast<size_t>(body_->field)][e_];
  const double rho = mu * p.scalars[static_cast<size_t>(body_->rho_param)];
  const double E = mu * p.scalars[static_cast<size_t>(body_->E_param)];
  const double nu = p.scalars[static_cast<size_t>(body_->nu_param)];
  double f[kMaxLocalDofs], K[kMaxLocalDofs * kMaxLocalDofs];
  const bool want_K = S && c->cq != 0;
  el.internal_force(s.q.data(), E, nu, f, want_K ? K : nullptr);
  for (int i = 0; i < nd; ++i) r[i] += f[i];
  add_inertia(el, s, rho, body_->gravity, r);
  if (!S) return;
  if (want_K) S->topLeftCorner(nd, nd) += c->cq * Eigen::Map<const Eigen::MatrixXd>(K, nd, nd);
  if (c->ca != 0) {
    const auto M0 = el.unit_mass();
    for (int i = 0; i < el.num_nodes(); ++i)
      for (int j = 0; j < el.num_nodes(); ++j)
        for (int k = 0; k < 3; ++k) (*S)(3 * i + k, 3 * j + k) += c->ca * rho * M0(i, j);
  }
}

void SolidForce::param_derivative(const LocalState& s, const ModelParams& p, int j,
                                  LocalVec& dr) const {
  if (!uses_parameter(j)) return;
  const SolidElement& el = *body_->elements[static_cast<size_t>(e_)];
  const int nd = el.num_dofs();
  const double mu = p.fields[static_cast<size_t>(body_->field)][e_];
  const double E0 = p.scalars[static_cast<size_t>(body_->E_param)];
  const double nu = p.scalars[static_cast<size_t>(body_->nu_param)];
  double f[kMaxLocalDofs];
  if (j == body_->E_param) {
    el.internal_force(s.q.data(), mu, nu, f, nullptr);  // ∂f_int/∂E0 = f_int at E = μ
    for (int i = 0; i < nd; ++i) dr[i] += f[i];
  }
  if (j == body_->nu_param) {
    el.internal_force_nu_derivative(s.q.data(), mu * E0, nu, f);
    for (int i = 0; i < nd; ++i) dr[i] += f[i];
  }
  if (j == body_->rho_param) add_inertia(el, s, mu, body_->gravity, dr);
}

void SolidForce::mass_damping(const LocalState&, const ModelParams& p, LocalMat& M,
                              LocalMat& C) const {
  const SolidElement& el = *body_->elements[static_cast<size_t>(e_)];
  const double m = p.fields[static_cast<size_t>(body_->field)][e_] *
                   p.scalars[static_cast<size_t>(body_->rho_param)];
  const auto M0 = el.unit_mass();
  const int nd = el.num_dofs();
  M.setZero(nd, nd);
  C.setZero(nd, nd);
  for (int i = 0; i < el.num_nodes(); ++i)
    for (int j = 0; j < el.num_nodes(); ++j)
      for (int k = 0; k < 3; ++k) M(3 * i + k, 3 * j + k) = m * M0(i, j);
}

void SolidForce::field_derivative(const LocalState& s, const ModelParams& p, LocalVec& dr) const {
  LocalVec r = LocalVec::Zero(static_cast<Eigen::Index>(n_));
  evaluate(s, p, r, nullptr, nullptr);
  const double mu = p.fields[static_cast<size_t>(body_->field)][e_];
  dr.head(static_cast<Eigen::Index>(n_)) += r / mu;
}

SolidNodeLink::SolidNodeLink(int node_dof, int body_dof0, const Vec3& d_or_X)
    : ground_(body_dof0 < 0), d_(d_or_X) {
  for (int k = 0; k < 3; ++k) dofs_[n_++] = node_dof + k;
  if (!ground_)
    for (int k = 0; k < 12; ++k) dofs_[n_++] = body_dof0 + k;
}

void SolidNodeLink::evaluate(double, const LocalVec& q, const ModelParams&, LocalEqVec& phi,
                             LocalJac* J) const {
  phi.resize(3);
  Vec3 x = q.head<3>();
  if (ground_) {
    x -= d_;
  } else {
    x -= q.segment<3>(3);
    for (int k = 0; k < 3; ++k) x -= d_[k] * q.segment<3>(6 + 3 * k);
  }
  phi = x;
  if (!J) return;
  J->setZero(3, static_cast<Eigen::Index>(n_));
  J->leftCols<3>().setIdentity();
  if (!ground_) {
    J->middleCols<3>(3) = -Mat3::Identity();
    for (int k = 0; k < 3; ++k) J->middleCols<3>(6 + 3 * k) = -d_[k] * Mat3::Identity();
  }
}

void SolidNodeLink::hessian(double, const LocalVec&, const LocalEqVec&, LocalMat& H) const {
  H.setZero(static_cast<Eigen::Index>(n_), static_cast<Eigen::Index>(n_));
}

}  // namespace lsmbs
