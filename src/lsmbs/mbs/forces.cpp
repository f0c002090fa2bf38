#include "lsmbs/mbs/forces.hpp"

namespace lsmbs {

// ------------------------------------------------------------------ RigidInertia
RigidInertia::RigidInertia(int dof0, int mass_param, int inertia_param, Vec2 offset,
                           std::string what)
    : dofs_{dof0, dof0 + 1, dof0 + 2},
      m_(mass_param),
      J_(inertia_param),
      c_(offset),
      what_(std::move(what)) {}

void RigidInertia::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                            const Coefficients* co, LocalMat* S) const {
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

void RigidInertia::param_derivative(const LocalState& s, const ModelParams& p, int j,
                                    LocalVec& dr) const {
  // r is linear in m and J_c: ∂r/∂J_c = (0, 0, θ̈), ∂r/∂m = r at m = 1, J_c = 0.
  if (j == J_) dr[2] += s.a[2];
  if (j != m_) return;
  const double th = s.q[2], thd = s.v[2], thdd = s.a[2];
  const Vec2 Rc = rotation(th) * c_, Rpc = rotation_derivative(th) * c_;
  const Vec2 axy(s.a[0], s.a[1]), g = p.gravity;
  const Vec2 dxy = axy + thdd * Rpc - thd * thd * Rc - g;
  dr[0] += dxy.x();
  dr[1] += dxy.y();
  dr[2] += c_.squaredNorm() * thdd + Rpc.dot(axy - g);
}

// ------------------------------------------------------------------ NodeMass
void NodeMass::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                        const Coefficients* co, LocalMat* S) const {
  const double m = p.scalars[m_];
  r[0] += m * (s.a[0] - p.gravity.x());
  r[1] += m * (s.a[1] - p.gravity.y());
  if (S) {
    (*S)(0, 0) += co->ca * m;
    (*S)(1, 1) += co->ca * m;
  }
}

void NodeMass::param_derivative(const LocalState& s, const ModelParams& p, int j,
                                LocalVec& dr) const {
  if (j != m_) return;
  dr[0] += s.a[0] - p.gravity.x();
  dr[1] += s.a[1] - p.gravity.y();
}

// ------------------------------------------------------------------ SpringDamper
SpringDamper::SpringDamper(PointRef a, PointRef b, int k_param, int c_param, int l0_param,
                           std::string what)
    : a_(a), b_(b), k_(k_param), c_(c_param), l0_(l0_param), what_(std::move(what)) {
  a_.append_dofs(dofs_);
  b_.append_dofs(dofs_);
}

void SpringDamper::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                            const Coefficients* co, LocalMat* S) const {
  const int na = a_.num_dofs(), nd = static_cast<int>(dofs_.size());
  const double k = p.scalars[k_], c = c_ >= 0 ? p.scalars[c_] : 0.0, l0 = p.scalars[l0_];
  const Vec2 d =
      PointKinematics::position(b_, s.q.data() + na) - PointKinematics::position(a_, s.q.data());
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
  if (a_.kind == PointRef::Kind::kBody)
    Hn(2, 2) -= PointKinematics::hess_thetatheta(a_, s.q.data(), n);
  if (b_.kind == PointRef::Kind::kBody)
    Hn(na + 2, na + 2) += PointKinematics::hess_thetatheta(b_, s.q.data() + na, n);
  const Mat2 P = (Mat2::Identity() - n * n.transpose()) / l;
  const LocalMat Lqq = D.transpose() * P * D + Hn;  // ∂²l/∂q²
  const LocalVec ldot_q = Lqq * s.v;                // ∂l̇/∂q
  S->noalias() += co->cq * (g * (k * g + c * ldot_q).transpose() + T * Lqq);
  S->noalias() += co->cv * c * g * g.transpose();
}

void SpringDamper::param_derivative(const LocalState& s, const ModelParams& p, int j,
                                    LocalVec& dr) const {
  // r = T ∂l/∂q with T = k (l − l0) + c l̇: ∂r/∂k = (l − l0) ∂l/∂q, ∂r/∂c = l̇ ∂l/∂q,
  // ∂r/∂l0 = −k ∂l/∂q.
  if (!uses_parameter(j)) return;
  const int na = a_.num_dofs(), nd = static_cast<int>(dofs_.size());
  const Vec2 d =
      PointKinematics::position(b_, s.q.data() + na) - PointKinematics::position(a_, s.q.data());
  Eigen::Matrix<double, 2, Eigen::Dynamic, 0, 2, kMaxLocalDofs> D;
  D.setZero(2, nd);
  PointKinematics::jacobian(a_, s.q.data(), D, 0, 0, -1.0);
  PointKinematics::jacobian(b_, s.q.data() + na, D, 0, na, 1.0);
  const double l = d.norm();
  if (!(l > 0)) return;  // as evaluate(): no force where the direction is undefined
  const Vec2 n = d / l;
  const LocalVec g = D.transpose() * n;
  double w = 0;  // ∂T/∂p_j
  if (j == k_) w += l - p.scalars[l0_];
  if (j == c_) w += n.dot(D * s.v);
  if (j == l0_) w -= p.scalars[k_];
  dr += w * g;
}

// ------------------------------------------------------------------ PointForce
PointForce::PointForce(PointRef a, std::shared_ptr<const TimeLaw> fx,
                       std::shared_ptr<const TimeLaw> fy, int scale_param, std::string what)
    : a_(a), fx_(std::move(fx)), fy_(std::move(fy)), scale_(scale_param), what_(std::move(what)) {
  a_.append_dofs(dofs_);
}

void PointForce::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                          const Coefficients* co, LocalMat* S) const {
  const double sc = scale_ >= 0 ? p.scalars[scale_] : 1.0;
  const Vec2 F = sc * Vec2(fx_->value(s.t), fy_->value(s.t));
  Eigen::Matrix<double, 2, 3> J = Eigen::Matrix<double, 2, 3>::Zero();
  PointKinematics::jacobian(a_, s.q.data(), J, 0, 0, 1.0);
  for (size_t j = 0; j < dofs_.size(); ++j) r[j] -= F.dot(J.col(j));
  if (S && a_.kind == PointRef::Kind::kBody)
    (*S)(2, 2) -= co->cq * PointKinematics::hess_thetatheta(a_, s.q.data(), F);
}

void PointForce::param_derivative(const LocalState& s, const ModelParams&, int j,
                                  LocalVec& dr) const {
  if (j != scale_) return;
  const Vec2 F(fx_->value(s.t), fy_->value(s.t));  // ∂(scale F)/∂scale
  Eigen::Matrix<double, 2, 3> J = Eigen::Matrix<double, 2, 3>::Zero();
  PointKinematics::jacobian(a_, s.q.data(), J, 0, 0, 1.0);
  for (size_t k = 0; k < dofs_.size(); ++k) dr[k] -= F.dot(J.col(k));
}

// ------------------------------------------------------------------ PressureForce
PressureForce::PressureForce(PointRef a, Vec2 u, int area_param, Table1D table, int angle_dof,
                             double offset, std::string what)
    : a_(a),
      u_(u.normalized()),
      area_(area_param),
      table_(std::move(table)),
      angle_dof_(angle_dof),
      offset_(offset),
      what_(std::move(what)) {
  a_.append_dofs(dofs_);
  if (angle_dof_ >= 0) dofs_.push_back(angle_dof_);
}

double PressureForce::pressure(double t, double angle) const {
  return table_.value(angle_dof_ >= 0 ? angle + offset_ : t + offset_);
}

void PressureForce::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                             const Coefficients* co, LocalMat* S) const {
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
  if (a_.kind == PointRef::Kind::kBody)
    (*S)(2, 2) -= co->cq * PointKinematics::hess_thetatheta(a_, s.q.data(), F);
  if (angle_dof_ >= 0)
    for (int j = 0; j < na; ++j) (*S)(j, na) -= co->cq * A * dP * u_.dot(J.col(j));
}

void PressureForce::param_derivative(const LocalState& s, const ModelParams&, int j,
                                     LocalVec& dr) const {
  if (j != area_) return;
  const int na = a_.num_dofs();
  const double P = table_.value(angle_dof_ >= 0 ? s.q[na] + offset_ : s.t + offset_);  // F = A P u
  Eigen::Matrix<double, 2, 3> J = Eigen::Matrix<double, 2, 3>::Zero();
  PointKinematics::jacobian(a_, s.q.data(), J, 0, 0, 1.0);
  for (int k = 0; k < na; ++k) dr[k] -= P * u_.dot(J.col(k));
}

// ------------------------------------------------------------------ Torque
Torque::Torque(int theta_dof, std::shared_ptr<const TimeLaw> law, int scale_param, std::string what)
    : dofs_{theta_dof}, law_(std::move(law)), scale_(scale_param), what_(std::move(what)) {}

void Torque::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients*,
                      LocalMat*) const {
  const double sc = scale_ >= 0 ? p.scalars[scale_] : 1.0;
  r[0] -= sc * law_->value(s.t);
}

void Torque::param_derivative(const LocalState& s, const ModelParams&, int j, LocalVec& dr) const {
  if (j == scale_) dr[0] -= law_->value(s.t);
}

// ------------------------------------------------------------------ RotationalSpringDamper
RotationalSpringDamper::RotationalSpringDamper(int theta_a, int theta_b, int k_param, int c_param,
                                               int free_angle_param, std::string what)
    : dofs_{theta_a}, k_(k_param), c_(c_param), th0_(free_angle_param), what_(std::move(what)) {
  if (theta_b >= 0) dofs_.push_back(theta_b);
}

void RotationalSpringDamper::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                                      const Coefficients* co, LocalMat* S) const {
  const bool two = dofs_.size() == 2;
  const double k = p.scalars[k_], c = c_ >= 0 ? p.scalars[c_] : 0.0, th0 = p.scalars[th0_];
  const double rel = s.q[0] - (two ? s.q[1] : 0.0), rel_dot = s.v[0] - (two ? s.v[1] : 0.0);
  const double M = k * (rel - th0) + c * rel_dot;
  r[0] += M;
  if (two) r[1] -= M;
  if (!S) return;
  const double w = co->cq * k + co->cv * c;  // ∂M/∂θa = k, ∂M/∂θ̇a = c
  (*S)(0, 0) += w;
  if (!two) return;
  (*S)(0, 1) -= w;
  (*S)(1, 0) -= w;
  (*S)(1, 1) += w;
}

void RotationalSpringDamper::param_derivative(const LocalState& s, const ModelParams& p, int j,
                                              LocalVec& dr) const {
  const bool two = dofs_.size() == 2;
  double w = 0;  // ∂M/∂p_j
  if (j == k_) w += s.q[0] - (two ? s.q[1] : 0.0) - p.scalars[th0_];
  if (j == c_) w += s.v[0] - (two ? s.v[1] : 0.0);
  if (j == th0_) w -= p.scalars[k_];
  dr[0] += w;
  if (two) dr[1] -= w;
}

}  // namespace lsmbs
