#include "lsmbs/mbs/constraints.hpp"

namespace lsmbs {

PointCoincidence::PointCoincidence(PointRef a, PointRef b) : a_(a), b_(b) {
  a_.append_dofs(dofs_);
  b_.append_dofs(dofs_);
}

void PointCoincidence::evaluate(double, const LocalVec& q, const ModelParams&, LocalEqVec& phi,
                                LocalJac* J) const {
  const int na = a_.num_dofs();
  phi = PointKinematics::position(a_, q.data()) - PointKinematics::position(b_, q.data() + na);
  if (J) {
    J->setZero(2, dofs_.size());
    PointKinematics::jacobian(a_, q.data(), *J, 0, 0, 1.0);
    PointKinematics::jacobian(b_, q.data() + na, *J, 0, na, -1.0);
  }
}

void PointCoincidence::hessian(double, const LocalVec& q, const LocalEqVec& w, LocalMat& H) const {
  const int na = a_.num_dofs(), n = static_cast<int>(dofs_.size());
  H.setZero(n, n);
  const Vec2 w2(w[0], w[1]);
  if (a_.kind == PointRef::Kind::kBody)
    H(2, 2) += PointKinematics::hess_thetatheta(a_, q.data(), w2);
  if (b_.kind == PointRef::Kind::kBody)
    H(na + 2, na + 2) -= PointKinematics::hess_thetatheta(b_, q.data() + na, w2);
}

Prismatic::Prismatic(PointRef a, Vec2 x0, Vec2 u, bool lock_rotation, double theta0)
    : a_(a), x0_(x0), lock_(lock_rotation && a.kind == PointRef::Kind::kBody), theta0_(theta0) {
  u.normalize();
  n_ = Vec2(-u.y(), u.x());
  a_.append_dofs(dofs_);
}

void Prismatic::evaluate(double, const LocalVec& q, const ModelParams&, LocalEqVec& phi,
                         LocalJac* J) const {
  phi.resize(size());
  phi[0] = n_.dot(PointKinematics::position(a_, q.data()) - x0_);
  if (lock_) phi[1] = q[2] - theta0_;
  if (J) {
    J->setZero(size(), dofs_.size());
    Eigen::Matrix<double, 2, 3> Ja = Eigen::Matrix<double, 2, 3>::Zero();
    PointKinematics::jacobian(a_, q.data(), Ja, 0, 0, 1.0);
    for (size_t j = 0; j < dofs_.size(); ++j) (*J)(0, j) = n_.dot(Ja.col(j));
    if (lock_) (*J)(1, 2) = 1;
  }
}

void Prismatic::hessian(double, const LocalVec& q, const LocalEqVec& w, LocalMat& H) const {
  const int n = static_cast<int>(dofs_.size());
  H.setZero(n, n);
  if (a_.kind == PointRef::Kind::kBody)
    H(2, 2) = PointKinematics::hess_thetatheta(a_, q.data(), w[0] * n_);
}

AngleDriver::AngleDriver(int theta_a_dof, int theta_b_dof, std::shared_ptr<const TimeLaw> law)
    : law_(std::move(law)) {
  if (theta_a_dof >= 0) dofs_.push_back(theta_a_dof);
  dofs_.push_back(theta_b_dof);
}

void AngleDriver::evaluate(double t, const LocalVec& q, const ModelParams&, LocalEqVec& phi,
                           LocalJac* J) const {
  phi.resize(1);
  const bool rel = dofs_.size() == 2;
  phi[0] = q[dofs_.size() - 1] - (rel ? q[0] : 0.0) - law_->value(t);
  if (J) {
    J->setZero(1, dofs_.size());
    (*J)(0, dofs_.size() - 1) = 1;
    if (rel) (*J)(0, 0) = -1;
  }
}

void AngleDriver::time_derivatives(double t, LocalEqVec& phi_t, LocalEqVec& phi_tt) const {
  double s, sd, sdd;
  law_->eval(t, s, sd, sdd);
  phi_t.setConstant(1, -sd);
  phi_tt.setConstant(1, -sdd);
}

TranslationDriver::TranslationDriver(PointRef a, Vec2 x0, Vec2 u,
                                     std::shared_ptr<const TimeLaw> law)
    : a_(a), x0_(x0), u_(u.normalized()), law_(std::move(law)) {
  a_.append_dofs(dofs_);
}

void TranslationDriver::evaluate(double t, const LocalVec& q, const ModelParams&, LocalEqVec& phi,
                                 LocalJac* J) const {
  phi.resize(1);
  phi[0] = u_.dot(PointKinematics::position(a_, q.data()) - x0_) - law_->value(t);
  if (J) {
    J->setZero(1, dofs_.size());
    Eigen::Matrix<double, 2, 3> Ja = Eigen::Matrix<double, 2, 3>::Zero();
    PointKinematics::jacobian(a_, q.data(), Ja, 0, 0, 1.0);
    for (size_t j = 0; j < dofs_.size(); ++j) (*J)(0, j) = u_.dot(Ja.col(j));
  }
}

void TranslationDriver::hessian(double, const LocalVec& q, const LocalEqVec& w, LocalMat& H) const {
  const int n = static_cast<int>(dofs_.size());
  H.setZero(n, n);
  if (a_.kind == PointRef::Kind::kBody)
    H(2, 2) = PointKinematics::hess_thetatheta(a_, q.data(), w[0] * u_);
}

void TranslationDriver::time_derivatives(double t, LocalEqVec& phi_t, LocalEqVec& phi_tt) const {
  double s, sd, sdd;
  law_->eval(t, s, sd, sdd);
  phi_t.setConstant(1, -sd);
  phi_tt.setConstant(1, -sdd);
}

Vec2 PointKinematics::position(const PointRef& p, const double* q) {
  switch (p.kind) {
    case PointRef::Kind::kGround:
      return p.local;
    case PointRef::Kind::kNode:
      return Vec2(q[0], q[1]);
    case PointRef::Kind::kBody:
      return Vec2(q[0], q[1]) + rotation(q[2]) * p.local;
  }
  return Vec2::Zero();
}

}  // namespace lsmbs
