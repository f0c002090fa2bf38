#include "lsmbs/mbs/spatial.hpp"

namespace lsmbs {

SpatialRigidInertia::SpatialRigidInertia(int dof0, int mass_param,
                                         std::array<int, 3> inertia_params, Vec3 gravity,
                                         std::string what)
    : m_(mass_param), I_(inertia_params), g_(std::move(gravity)), what_(std::move(what)) {
  for (int i = 0; i < 12; ++i) dofs_[static_cast<size_t>(i)] = dof0 + i;
}

Vec3 SpatialRigidInertia::second_moments(const Vec3& I) {
  return Vec3(I[1] + I[2] - I[0], I[2] + I[0] - I[1], I[0] + I[1] - I[2]) / 2;
}

Vec3 SpatialRigidInertia::second_moments(const ModelParams& p) const {
  return second_moments(Vec3(p.scalars[static_cast<size_t>(I_[0])],
                             p.scalars[static_cast<size_t>(I_[1])],
                             p.scalars[static_cast<size_t>(I_[2])]));
}

bool SpatialRigidInertia::uses_parameter(int j) const {
  return j == m_ || j == I_[0] || j == I_[1] || j == I_[2];
}

void SpatialRigidInertia::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                                   const Coefficients* c, LocalMat* S) const {
  const double m = p.scalars[static_cast<size_t>(m_)];
  const Vec3 J = second_moments(p);
  // r = M q̈ − m g on the centre of mass (no velocity-dependent term: M is constant)
  for (int i = 0; i < 3; ++i) r[i] += m * (s.a[i] - g_[i]);
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) r[3 + 3 * k + i] += J[k] * s.a[3 + 3 * k + i];
  if (!S) return;
  for (int i = 0; i < 3; ++i) (*S)(i, i) += c->ca * m;
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) (*S)(3 + 3 * k + i, 3 + 3 * k + i) += c->ca * J[k];
}

void SpatialRigidInertia::mass_damping(const LocalState& /*s*/, const ModelParams& p, LocalMat& M,
                                       LocalMat& C) const {
  M.setZero(12, 12);
  C.setZero(12, 12);
  const double m = p.scalars[static_cast<size_t>(m_)];
  const Vec3 J = second_moments(p);
  for (int i = 0; i < 3; ++i) M(i, i) = m;
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) M(3 + 3 * k + i, 3 + 3 * k + i) = J[k];
}

void SpatialRigidInertia::param_derivative(const LocalState& s, const ModelParams& /*p*/, int j,
                                           LocalVec& dr) const {
  // r is linear in m and in the principal moments: ∂J_k/∂I_l = +½ (l ≠ k), −½ (l = k)
  if (j == m_)
    for (int i = 0; i < 3; ++i) dr[i] += s.a[i] - g_[i];
  for (int l = 0; l < 3; ++l) {
    if (j != I_[static_cast<size_t>(l)]) continue;
    for (int k = 0; k < 3; ++k) {
      const double dJ = k == l ? -0.5 : 0.5;
      for (int i = 0; i < 3; ++i) dr[3 + 3 * k + i] += dJ * s.a[3 + 3 * k + i];
    }
  }
}

SpatialFrameConstraint::SpatialFrameConstraint(int dof0, Kind kind) : kind_(kind) {
  for (int i = 0; i < 9; ++i) dofs_[static_cast<size_t>(i)] = dof0 + 3 + i;
}

void SpatialFrameConstraint::evaluate(double /*t*/, const LocalVec& q, const ModelParams& /*p*/,
                                      LocalEqVec& phi, LocalJac* J) const {
  phi.setZero(3);
  if (J) J->setZero(3, 9);
  const auto e = [&](int k) { return q.segment<3>(3 * k); };
  for (int i = 0; i < 3; ++i) {
    if (kind_ == Kind::kNormal) {
      phi[i] = 0.5 * (e(i).squaredNorm() - 1);
      if (J) J->block<1, 3>(i, 3 * i) = e(i).transpose();
    } else {
      // equation i couples the other two vectors: (1, 2), (2, 0), (0, 1)
      const int a = (i + 1) % 3, b = (i + 2) % 3;
      phi[i] = e(a).dot(e(b));
      if (J) {
        J->block<1, 3>(i, 3 * a) = e(b).transpose();
        J->block<1, 3>(i, 3 * b) = e(a).transpose();
      }
    }
  }
}

void SpatialFrameConstraint::hessian(double /*t*/, const LocalVec& /*q*/, const LocalEqVec& w,
                                     LocalMat& H) const {
  H.setZero(9, 9);
  for (int i = 0; i < 3; ++i) {
    if (kind_ == Kind::kNormal) {
      H.block<3, 3>(3 * i, 3 * i) += w[i] * Mat3::Identity();
    } else {
      const int a = (i + 1) % 3, b = (i + 2) % 3;
      H.block<3, 3>(3 * a, 3 * b) += w[i] * Mat3::Identity();
      H.block<3, 3>(3 * b, 3 * a) += w[i] * Mat3::Identity();
    }
  }
}

SpatialGroundSpherical::SpatialGroundSpherical(int dof0, Vec3 body_point, Vec3 ground_point)
    : d_(std::move(body_point)), p0_(std::move(ground_point)) {
  for (int i = 0; i < 12; ++i) dofs_[static_cast<size_t>(i)] = dof0 + i;
}

void SpatialGroundSpherical::evaluate(double /*t*/, const LocalVec& q, const ModelParams& /*p*/,
                                      LocalEqVec& phi, LocalJac* J) const {
  phi = q.segment<3>(0) - p0_;
  for (int k = 0; k < 3; ++k) phi += d_[k] * q.segment<3>(3 + 3 * k);
  if (!J) return;
  J->setZero(3, 12);
  J->block<3, 3>(0, 0) = Mat3::Identity();
  for (int k = 0; k < 3; ++k) J->block<3, 3>(0, 3 + 3 * k) = d_[k] * Mat3::Identity();
}

void SpatialPose::write(int dof0, Vec& q) const {
  q.segment<3>(dof0) = r;
  for (int k = 0; k < 3; ++k) q.segment<3>(dof0 + 3 + 3 * k) = R.col(k);
}

void SpatialPose::write_rates(int dof0, const Mat3& R, const Vec3& rdot, const Vec3& Omega,
                              Vec& v) {
  Mat3 W;
  W << 0, -Omega.z(), Omega.y(), Omega.z(), 0, -Omega.x(), -Omega.y(), Omega.x(), 0;
  const Mat3 Rdot = R * W;
  v.segment<3>(dof0) = rdot;
  for (int k = 0; k < 3; ++k) v.segment<3>(dof0 + 3 + 3 * k) = Rdot.col(k);
}

SpatialPose SpatialPose::read(int dof0, const Vec& q) {
  SpatialPose P;
  P.r = q.segment<3>(dof0);
  for (int k = 0; k < 3; ++k) P.R.col(k) = q.segment<3>(dof0 + 3 + 3 * k);
  return P;
}

Vec3 SpatialPose::body_angular_velocity(int dof0, const Vec& q, const Vec& v) {
  const auto e = [&](int k) -> Vec3 { return q.segment<3>(dof0 + 3 + 3 * k); };
  const auto ed = [&](int k) -> Vec3 { return v.segment<3>(dof0 + 3 + 3 * k); };
  // RᵀṘ = [Ω]ₓ: Ω₁ = e₃·ė₂, Ω₂ = e₁·ė₃, Ω₃ = e₂·ė₁
  return Vec3(e(2).dot(ed(1)), e(0).dot(ed(2)), e(1).dot(ed(0)));
}

}  // namespace lsmbs
