#include "lsmbs/mbs/spatial_force.hpp"

namespace lsmbs {

namespace {

Mat3 skew(const Vec3& w) {
  Mat3 W;
  W << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return W;
}

}  // namespace

// ------------------------------------------------------------------ SpatialLoad
SpatialLoad::SpatialLoad(int dof0, Kind kind, Frame frame, const Vec3& body_point,
                         std::array<std::shared_ptr<const TimeLaw>, 3> laws, int scale_param,
                         std::string what)
    : kind_(kind),
      frame_(frame),
      d_(body_point),
      laws_(std::move(laws)),
      scale_(scale_param),
      what_(std::move(what)) {
  for (int i = 0; i < 12; ++i) dofs_[static_cast<size_t>(i)] = dof0 + i;
}

void SpatialLoad::add(const LocalState& s, double scale, LocalVec& r, double cq,
                      LocalMat* S) const {
  Vec3 L = Vec3::Zero();  // components, ground or body frame
  for (int j = 0; j < 3; ++j) {
    if (!laws_[static_cast<size_t>(j)]) continue;
    double v, vd, vdd;
    laws_[static_cast<size_t>(j)]->eval(s.t, v, vd, vdd);
    L[j] = scale * v;
  }
  const auto e = [&](int k) -> Vec3 { return s.q.segment<3>(3 + 3 * k); };
  Vec3 W = L;  // the load in global components
  if (frame_ == Frame::kBody) W = L[0] * e(0) + L[1] * e(1) + L[2] * e(2);
  // eq. (7): f_ext enters the residual with a minus sign; S gets −c_q ∂Q/∂q
  if (kind_ == Kind::kForce) {
    r.segment<3>(0) -= W;
    for (int k = 0; k < 3; ++k) r.segment<3>(3 + 3 * k) -= d_[k] * W;
    if (!S || frame_ == Frame::kGround) return;
    // ∂W/∂e_j = L_j I; rows r (weight 1) and e_k (weight d_k)
    for (int j = 0; j < 3; ++j) {
      (*S).block<3, 3>(0, 3 + 3 * j) -= cq * L[j] * Mat3::Identity();
      for (int k = 0; k < 3; ++k)
        (*S).block<3, 3>(3 + 3 * k, 3 + 3 * j) -= cq * d_[k] * L[j] * Mat3::Identity();
    }
    return;
  }
  for (int k = 0; k < 3; ++k) r.segment<3>(3 + 3 * k) -= 0.5 * W.cross(e(k));
  if (!S) return;
  // Q_k = ½ W × e_k: ∂Q_k/∂e_k = ½ [W]ₓ; body frame also ∂W/∂e_j = L_j I, so
  // ∂Q_k/∂e_j += −½ L_j [e_k]ₓ
  for (int k = 0; k < 3; ++k) {
    (*S).block<3, 3>(3 + 3 * k, 3 + 3 * k) -= cq * 0.5 * skew(W);
    if (frame_ == Frame::kBody)
      for (int j = 0; j < 3; ++j)
        (*S).block<3, 3>(3 + 3 * k, 3 + 3 * j) += cq * 0.5 * L[j] * skew(e(k));
  }
}

void SpatialLoad::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                           const Coefficients* c, LocalMat* S) const {
  add(s, p.scalars[static_cast<size_t>(scale_)], r, c ? c->cq : 0.0, S);
}

void SpatialLoad::param_derivative(const LocalState& s, const ModelParams& /*p*/, int j,
                                   LocalVec& dr) const {
  if (j == scale_) add(s, 1.0, dr, 0.0, nullptr);  // r is linear in the scale
}

// ------------------------------------------------------------------ SpatialSpringDamper
SpatialSpringDamper::SpatialSpringDamper(SpatialBody a, const Vec3& da, SpatialBody b,
                                         const Vec3& db, int k_param, int c_param,
                                         int free_length_param, std::string what)
    : block_(a, b), k_(k_param), c_(c_param), l0_(free_length_param), what_(std::move(what)) {
  gap_ = block_.point(1, db).minus(block_.point(0, da));
}

double SpatialSpringDamper::length(const Vec& q) const {
  const auto d = block_.dofs();
  LocalVec z(static_cast<Eigen::Index>(d.size()));
  for (size_t i = 0; i < d.size(); ++i) z[static_cast<Eigen::Index>(i)] = q[d[i]];
  return gap_.value(z).norm();
}

void SpatialSpringDamper::evaluate(const LocalState& s, const ModelParams& p, LocalVec& r,
                                   const Coefficients* co, LocalMat* S) const {
  const double k = p.scalars[static_cast<size_t>(k_)];
  const double c = c_ >= 0 ? p.scalars[static_cast<size_t>(c_)] : 0.0;
  const double l0 = p.scalars[static_cast<size_t>(l0_)];
  const Vec3 d = gap_.value(s.q);
  const double l = d.norm();
  if (!(l > 0)) return;  // coincident points: direction undefined (reported by the model check)
  const Vec3 n = d / l;
  const double ldot = n.dot(gap_.A * s.v);
  const double T = k * (l - l0) + c * ldot;
  const LocalVec g = gap_.A.transpose() * n;  // ∂l/∂q
  r += T * g;
  if (!S) return;
  const Mat3 P = (Mat3::Identity() - n * n.transpose()) / l;
  const LocalMat Lqq = gap_.A.transpose() * P * gap_.A;  // ∂²l/∂q²
  const LocalVec ldot_q = Lqq * s.v;                     // ∂l̇/∂q
  S->noalias() += co->cq * (g * (k * g + c * ldot_q).transpose() + T * Lqq);
  S->noalias() += co->cv * c * g * g.transpose();
}

void SpatialSpringDamper::param_derivative(const LocalState& s, const ModelParams& p, int j,
                                           LocalVec& dr) const {
  if (!uses_parameter(j)) return;
  const Vec3 d = gap_.value(s.q);
  const double l = d.norm();
  if (!(l > 0)) return;
  const Vec3 n = d / l;
  double w = 0;  // ∂T/∂p_j
  if (j == k_) w += l - p.scalars[static_cast<size_t>(l0_)];
  if (j == c_) w += n.dot(gap_.A * s.v);
  if (j == l0_) w -= p.scalars[static_cast<size_t>(k_)];
  dr += w * (gap_.A.transpose() * n);
}

}  // namespace lsmbs
