#include "lsmbs/mbs/forces.hpp"

namespace lsmbs {

// ------------------------------------------------------------------ RigidInertia
RigidInertia::RigidInertia(int dof0, int mass_param, int inertia_param, Vec2 offset, std::string what)
    : dofs_{dof0, dof0 + 1, dof0 + 2}, m_(mass_param), J_(inertia_param), c_(offset), what_(std::move(what)) {}

void RigidInertia::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* co,
                            LocalMat* S) const {
  const double m = p.scalars[m_], Jc = J_ >= 0 ? p.scalars[J_] : 0.0;
  const double th = s.q[2], thd = s.v[2], thdd = s.a[2];
  const Vec2 Rc = rotation(th) * c_, Rpc = rotation_derivative(th) * c_;
  const Vec2 axy(s.a[0], s.a[1]), g = p.gravity;
  // r = M a + f_gyr − f_gravity
  const Vec2 rxy = m * (axy + thdd * Rpc - thd * thd * Rc - g);
  r[0] += rxy.x();
  r[1] += rxy.y();
  r[2] += (Jc + m * c_.squaredNorm()) * thdd + m * Rpc.dot(axy - g);
  if (!S) return;
  const double ca = co->ca, cv = co->cv, cq = co->cq;
  // M
  (*S)(0, 0) += ca * m;
  (*S)(1, 1) += ca * m;
  (*S)(0, 2) += ca * m * Rpc.x();
  (*S)(1, 2) += ca * m * Rpc.y();
  (*S)(2, 0) += ca * m * Rpc.x();
  (*S)(2, 1) += ca * m * Rpc.y();
  (*S)(2, 2) += ca * (Jc + m * c_.squaredNorm());
  // C = ∂r/∂θ̇ (column θ)
  (*S)(0, 2) += cv * (-2 * m * thd * Rc.x());
  (*S)(1, 2) += cv * (-2 * m * thd * Rc.y());
  // K = ∂r/∂θ (column θ); R''c = −Rc
  const Vec2 kx = m * (-thdd * Rc - thd * thd * Rpc);
  (*S)(0, 2) += cq * kx.x();
  (*S)(1, 2) += cq * kx.y();
  (*S)(2, 2) += cq * (-m * Rc.dot(axy - g));
}

// ------------------------------------------------------------------ NodeMass
void NodeMass::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* co,
                        LocalMat* S) const {
  const double m = p.scalars[m_];
  r[0] += m * (s.a[0] - p.gravity.x());
  r[1] += m * (s.a[1] - p.gravity.y());
  if (S) {
    (*S)(0, 0) += co->ca * m;
    (*S)(1, 1) += co->ca * m;
  }
}

// ------------------------------------------------------------------ SpringDamper
SpringDamper::SpringDamper(PointRef a, PointRef b, int k_param, int c_param, int l0_param, std::string what)
    : a_(a), b_(b), k_(k_param), c_(c_param), l0_(l0_param), what_(std::move(what)) {
  a_.append_dofs(dofs_);
  b_.append_dofs(dofs_);
}

void SpringDamper::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* co,
                            LocalMat* S) const {
  const int na = a_.num_dofs(), nd = static_cast<int>(dofs_.size());
  const double k = p.scalars[k_], c = c_ >= 0 ? p.scalars[c_] : 0.0, l0 = p.scalars[l0_];
  const Vec2 d = PointKinematics::position(b_, s.q.data() + na) - PointKinematics::position(a_, s.q.data());
  Eigen::Matrix<double, 2, Eigen::Dynamic, 0, 2, kMaxLocalDofs> D;
  D.setZero(2, nd);
  PointKinematics::jacobian(a_, s.q.data(), D, 0, 0, -1.0);
  PointKinematics::jacobian(b_, s.q.data() + na, D, 0, na, 1.0);
  const double l = d.norm();
  if (!(l > 0)) return;  // coincident points: direction undefined (reported by the model check)
  const Vec2 n = d / l;
  const Vec2 dd = D * s.v;
  const double ldot = n.dot(dd);
  const double T = k * (l - l0) + c * ldot;
  const LocalVec g = D.transpose() * n;  // ∂l/∂q
  r += T * g;
  if (!S) return;
  // H(n): Σ_a n_a ∂²d_a/∂q²
  LocalMat Hn = LocalMat::Zero(nd, nd);
  if (a_.kind == PointRef::Kind::kBody) Hn(2, 2) -= PointKinematics::hess_thetatheta(a_, s.q.data(), n);
  if (b_.kind == PointRef::Kind::kBody) Hn(na + 2, na + 2) += PointKinematics::hess_thetatheta(b_, s.q.data() + na, n);
  const Mat2 P = (Mat2::Identity() - n * n.transpose()) / l;
  const LocalMat Lqq = D.transpose() * P * D + Hn;  // ∂²l/∂q²
  const LocalVec ldot_q = Lqq * s.v;                // ∂l̇/∂q
  S->noalias() += co->cq * (g * (k * g + c * ldot_q).transpose() + T * Lqq);
  S->noalias() += co->cv * c * g * g.transpose();
}

// ------------------------------------------------------------------ PointForce
PointForce::PointForce(PointRef a, std::shared_ptr<const TimeLaw> fx, std::shared_ptr<const TimeLaw> fy,
                       int scale_param, std::string what)
    : a_(a), fx_(std::move(fx)), fy_(std::move(fy)), scale_(scale_param), what_(std::move(what)) {
  a_.append_dofs(dofs_);
}

void PointForce::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* co,
                          LocalMat* S) const {
  const double sc = scale_ >= 0 ? p.scalars[scale_] : 1.0;
  const Vec2 F = sc * Vec2(fx_->value(s.t), fy_->value(s.t));
  Eigen::Matrix<double, 2, 3> J = Eigen::Matrix<double, 2, 3>::Zero();
  PointKinematics::jacobian(a_, s.q.data(), J, 0, 0, 1.0);
  for (size_t j = 0; j < dofs_.size(); ++j) r[j] -= F.dot(J.col(j));
  if (S && a_.kind == PointRef::Kind::kBody) (*S)(2, 2) -= co->cq * PointKinematics::hess_thetatheta(a_, s.q.data(), F);
}

// ------------------------------------------------------------------ PressureForce
PressureForce::PressureForce(PointRef a, Vec2 u, int area_param, Table1D table, int angle_dof, double offset,
                             std::string what)
    : a_(a), u_(u.normalized()), area_(area_param), table_(std::move(table)), angle_dof_(angle_dof),
      offset_(offset), what_(std::move(what)) {
  a_.append_dofs(dofs_);
  if (angle_dof_ >= 0) dofs_.push_back(angle_dof_);
}

double PressureForce::pressure(double t, double angle) const {
  return table_.value(angle_dof_ >= 0 ? angle + offset_ : t + offset_);
}

void PressureForce::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* co,
                             LocalMat* S) const {
  const int na = a_.num_dofs();
  const double arg = angle_dof_ >= 0 ? s.q[na] + offset_ : s.t + offset_;
  double P, dP, d2P;
  table_.eval(arg, P, dP, d2P);
  const double A = p.scalars[area_];
  const Vec2 F = A * P * u_;
  Eigen::Matrix<double, 2, 3> J = Eigen::Matrix<double, 2, 3>::Zero();
  PointKinematics::jacobian(a_, s.q.data(), J, 0, 0, 1.0);
  for (int j = 0; j < na; ++j) r[j] -= F.dot(J.col(j));
  if (!S) return;
  if (a_.kind == PointRef::Kind::kBody) (*S)(2, 2) -= co->cq * PointKinematics::hess_thetatheta(a_, s.q.data(), F);
  if (angle_dof_ >= 0)
    for (int j = 0; j < na; ++j) (*S)(j, na) -= co->cq * A * dP * u_.dot(J.col(j));
}

}  // namespace lsmbs
