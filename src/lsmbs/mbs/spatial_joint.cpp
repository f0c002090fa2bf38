#include "lsmbs/mbs/spatial_joint.hpp"

#include <cmath>
#include <stdexcept>

namespace lsmbs {

// ------------------------------------------------------------------ SpatialJointBlock
SpatialJointBlock::SpatialJointBlock(SpatialBody a, SpatialBody b) : body_{a, b} {
  for (const SpatialBody& s : body_)
    if (!s.ground())
      for (int i = 0; i < 12; ++i) dofs_[n_++] = s.dof0 + i;
}

int SpatialJointBlock::column(int side) const {
  if (body_[static_cast<size_t>(side)].ground()) return -1;
  return side == 1 && !body_[0].ground() ? 12 : 0;
}

SpatialAffine SpatialJointBlock::constant(const Vec3& c) const {
  SpatialAffine w;
  w.A.setZero(3, static_cast<Eigen::Index>(n_));
  w.c = c;
  return w;
}

SpatialAffine SpatialJointBlock::point(int side, const Vec3& d) const {
  const int c0 = column(side);
  if (c0 < 0) return constant(d);
  SpatialAffine w = constant(Vec3::Zero());
  w.A.block<3, 3>(0, c0) = Mat3::Identity();  // x = r + Σ d_k e_k
  for (int k = 0; k < 3; ++k) w.A.block<3, 3>(0, c0 + 3 + 3 * k) = d[k] * Mat3::Identity();
  return w;
}

SpatialAffine SpatialJointBlock::vector(int side, const Vec3& u) const {
  const int c0 = column(side);
  if (c0 < 0) return constant(u);
  SpatialAffine w = constant(Vec3::Zero());
  for (int k = 0; k < 3; ++k) w.A.block<3, 3>(0, c0 + 3 + 3 * k) = u[k] * Mat3::Identity();
  return w;
}

void SpatialJointBlock::add(SpatialAffine a, SpatialAffine b, double value, bool angular) {
  if (static_cast<int>(eq_.size()) >= kMaxLocalEqs)
    throw std::logic_error("SpatialJointBlock: more than kMaxLocalEqs equations");
  Equation e{std::move(a), std::move(b), value, angular, nullptr, {}, false};
  // the Hessian of a·b is constant: computed once here, added with its weight per iteration
  e.zero_hessian = e.a.A.isZero(0) || e.b.A.isZero(0);
  if (!e.zero_hessian) e.hessian = e.a.A.transpose() * e.b.A + e.b.A.transpose() * e.a.A;
  eq_.push_back(std::move(e));
}

void SpatialJointBlock::drive_last(std::shared_ptr<const TimeLaw> law) {
  eq_.back().law = std::move(law);
}

void SpatialJointBlock::evaluate(double t, const LocalVec& q, const ModelParams& /*p*/,
                                 LocalEqVec& phi, LocalJac* J) const {
  const auto m = static_cast<Eigen::Index>(eq_.size()), n = static_cast<Eigen::Index>(n_);
  phi.setZero(m);
  if (J) J->setZero(m, n);
  for (Eigen::Index i = 0; i < m; ++i) {
    const Equation& e = eq_[static_cast<size_t>(i)];
    const Vec3 a = e.a.value(q), b = e.b.value(q);
    double s = e.value;
    if (e.law) {
      double v, vd, vdd;
      e.law->eval(t, v, vd, vdd);
      s += v;
    }
    phi[i] = a.dot(b) - s;
    if (J) J->row(i) = b.transpose() * e.a.A + a.transpose() * e.b.A;
  }
}

void SpatialJointBlock::hessian(double /*t*/, const LocalVec& /*q*/, const LocalEqVec& w,
                                LocalMat& H) const {
  const auto n = static_cast<Eigen::Index>(n_);
  H.setZero(n, n);
  for (size_t i = 0; i < eq_.size(); ++i) {
    const Equation& e = eq_[i];
    const double wi = w[static_cast<Eigen::Index>(i)];
    if (wi != 0 && !e.zero_hessian) H += wi * e.hessian;
  }
}

void SpatialJointBlock::time_derivatives(double t, LocalEqVec& phi_t, LocalEqVec& phi_tt) const {
  const auto m = static_cast<Eigen::Index>(eq_.size());
  phi_t.setZero(m);
  phi_tt.setZero(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    const Equation& e = eq_[static_cast<size_t>(i)];
    if (!e.law) continue;
    double v, vd, vdd;
    e.law->eval(t, v, vd, vdd);
    phi_t[i] = -vd;
    phi_tt[i] = -vdd;
  }
}

void SpatialJointBlock::time_kinks(double t0, double t1, std::vector<double>& out) const {
  for (const Equation& e : eq_)
    if (e.law) e.law->kinks(t0, t1, out);
}

// ------------------------------------------------------------------ SpatialJointAngle
namespace {

// A body-fixed vector over the frame DOFs of one side: 9 columns from c0 (none for ground).
SpatialAffine frame_vector(int c0, const Vec3& u, Eigen::Index n) {
  SpatialAffine w;
  w.A.setZero(3, n);
  if (c0 < 0) {
    w.c = u;
    return w;
  }
  for (int k = 0; k < 3; ++k) w.A.block<3, 3>(0, c0 + 3 * k) = u[k] * Mat3::Identity();
  return w;
}

}  // namespace

SpatialJointAngle::SpatialJointAngle(SpatialBody a, SpatialBody b, const Vec3& a1, const Vec3& a2,
                                     const Vec3& b1, int theta_dof) {
  int ca = -1, cb = -1;
  if (!a.ground()) {
    ca = static_cast<int>(n_);
    for (int i = 3; i < 12; ++i) dofs_[n_++] = a.dof0 + i;
  }
  if (!b.ground()) {
    cb = static_cast<int>(n_);
    for (int i = 3; i < 12; ++i) dofs_[n_++] = b.dof0 + i;
  }
  theta_col_ = static_cast<int>(n_);
  dofs_[n_++] = theta_dof;
  const auto n = static_cast<Eigen::Index>(n_);
  a1_ = frame_vector(ca, a1, n);
  a2_ = frame_vector(ca, a2, n);
  b1_ = frame_vector(cb, b1, n);
}

void SpatialJointAngle::evaluate(double /*t*/, const LocalVec& q, const ModelParams& /*p*/,
                                 LocalEqVec& phi, LocalJac* J) const {
  const double th = q[theta_col_], c = std::cos(th), s = std::sin(th);
  const Vec3 a1 = a1_.value(q), a2 = a2_.value(q), b1 = b1_.value(q);
  const double P = a2.dot(b1), Q = a1.dot(b1);
  phi.setConstant(1, c * P - s * Q);
  if (!J) return;
  J->setZero(1, static_cast<Eigen::Index>(n_));
  // ∂P/∂z = b1ᵀA_a2 + a2ᵀA_b1, ∂Q/∂z = b1ᵀA_a1 + a1ᵀA_b1
  J->row(0) = c * (b1.transpose() * a2_.A + a2.transpose() * b1_.A) -
              s * (b1.transpose() * a1_.A + a1.transpose() * b1_.A);
  (*J)(0, theta_col_) = -s * P - c * Q;
}

void SpatialJointAngle::hessian(double /*t*/, const LocalVec& q, const LocalEqVec& w,
                                LocalMat& H) const {
  const auto n = static_cast<Eigen::Index>(n_);
  H.setZero(n, n);
  const double th = q[theta_col_], c = std::cos(th), s = std::sin(th), w0 = w[0];
  const Vec3 a1 = a1_.value(q), a2 = a2_.value(q), b1 = b1_.value(q);
  // Φ = c P(z) − s Q(z): P and Q bilinear in the frame vectors (constant Hessians).
  H.noalias() += w0 * c * (a2_.A.transpose() * b1_.A + b1_.A.transpose() * a2_.A);
  H.noalias() -= w0 * s * (a1_.A.transpose() * b1_.A + b1_.A.transpose() * a1_.A);
  const LocalVec gP = a2_.A.transpose() * b1 + b1_.A.transpose() * a2;
  const LocalVec gQ = a1_.A.transpose() * b1 + b1_.A.transpose() * a1;
  const LocalVec mixed = w0 * (-s * gP - c * gQ);  // ∂²Φ/∂z∂θ
  H.col(theta_col_) += mixed;
  H.row(theta_col_) += mixed.transpose();
  H(theta_col_, theta_col_) = w0 * (-c * a2.dot(b1) + s * a1.dot(b1));
}

// ------------------------------------------------------------------ joints
SpatialJointFrame SpatialJointFrame::about(const Vec3& point, const Vec3& axis) {
  SpatialJointFrame f;
  f.point = point;
  const Vec3 z = axis.normalized();
  // the global axis least aligned with z, made orthogonal to it
  Eigen::Index i = 0;
  z.cwiseAbs().minCoeff(&i);
  const Vec3 x = (Vec3::Unit(i) - z[i] * z).normalized();
  f.axes.col(0) = x;
  f.axes.col(1) = z.cross(x);
  f.axes.col(2) = z;
  return f;
}

bool spatial_joint_rotates(SpatialJointKind kind) {
  return kind == SpatialJointKind::kRevolute || kind == SpatialJointKind::kCylindrical;
}

bool spatial_joint_slides(SpatialJointKind kind) {
  return kind == SpatialJointKind::kPrismatic || kind == SpatialJointKind::kCylindrical;
}

namespace {

// The joint frame on one side in that body's principal frame (ground: global).
struct SideFrame {
  Vec3 point;
  Mat3 axes;
};
SideFrame side_frame(SpatialBody b, const SpatialPose& pose, const SpatialJointFrame& f) {
  if (b.ground()) return {f.point, f.axes};
  return {pose.R.transpose() * (f.point - pose.r), pose.R.transpose() * f.axes};
}

}  // namespace

std::vector<std::unique_ptr<ConstraintElement>> make_spatial_joint(
    SpatialJointKind kind, SpatialBody a, const SpatialPose& pose_a, SpatialBody b,
    const SpatialPose& pose_b, const SpatialJointFrame& f, int theta_dof) {
  using K = SpatialJointKind;
  const SideFrame fa = side_frame(a, pose_a, f), fb = side_frame(b, pose_b, f);
  std::vector<std::unique_ptr<ConstraintElement>> out;
  auto block = [&] {
    out.push_back(std::make_unique<SpatialJointBlock>(a, b));
    return static_cast<SpatialJointBlock*>(out.back().get());
  };
  const auto ax = [&](const SideFrame& s, int k) -> Vec3 { return s.axes.col(k); };
  // x_B − x_A as one affine map
  const auto gap = [&](SpatialJointBlock& j) {
    return j.point(1, fb.point).minus(j.point(0, fa.point));
  };
  if (kind == K::kSpherical || kind == K::kUniversal || kind == K::kRevolute || kind == K::kWeld) {
    SpatialJointBlock& j = *block();
    for (int i = 0; i < 3; ++i) j.add(j.constant(Vec3::Unit(i)), gap(j), 0, false);
  }
  if (kind == K::kUniversal) {
    SpatialJointBlock& j = *block();
    j.add(j.vector(0, ax(fa, 0)), j.vector(1, ax(fb, 1)), 0, true);
  }
  if (kind == K::kRevolute || kind == K::kCylindrical || kind == K::kPrismatic ||
      kind == K::kPlanar) {
    // the third axes stay parallel (planar: the normals)
    SpatialJointBlock& j = *block();
    j.add(j.vector(0, ax(fa, 0)), j.vector(1, ax(fb, 2)), 0, true);
    j.add(j.vector(0, ax(fa, 1)), j.vector(1, ax(fb, 2)), 0, true);
    if (kind == K::kPlanar) j.add(j.vector(0, ax(fa, 2)), gap(j), 0, false);
  }
  if (kind == K::kCylindrical || kind == K::kPrismatic || kind == K::kInline) {
    // x_B on the line through x_A along a3
    SpatialJointBlock& j = *block();
    j.add(j.vector(0, ax(fa, 0)), gap(j), 0, false);
    j.add(j.vector(0, ax(fa, 1)), gap(j), 0, false);
    if (kind == K::kPrismatic) j.add(j.vector(0, ax(fa, 0)), j.vector(1, ax(fb, 1)), 0, true);
  }
  if (kind == K::kWeld) {
    SpatialJointBlock& j = *block();
    for (int k = 0; k < 3; ++k)
      j.add(j.vector(0, ax(fa, k)), j.vector(1, ax(fb, (k + 1) % 3)), 0, true);
  }
  if (theta_dof >= 0 && spatial_joint_rotates(kind))
    out.push_back(
        std::make_unique<SpatialJointAngle>(a, b, ax(fa, 0), ax(fa, 1), ax(fb, 0), theta_dof));
  return out;
}

std::unique_ptr<ConstraintElement> make_spatial_translation_driver(
    SpatialBody a, const SpatialPose& pose_a, SpatialBody b, const SpatialPose& pose_b,
    const SpatialJointFrame& f, std::shared_ptr<const TimeLaw> law) {
  const SideFrame fa = side_frame(a, pose_a, f), fb = side_frame(b, pose_b, f);
  auto j = std::make_unique<SpatialJointBlock>(a, b);
  j->add(j->vector(0, fa.axes.col(2)), j->point(1, fb.point).minus(j->point(0, fa.point)), 0,
         false);
  j->drive_last(std::move(law));
  return j;
}

}  // namespace lsmbs
