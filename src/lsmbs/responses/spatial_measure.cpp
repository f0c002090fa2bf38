#include "lsmbs/responses/spatial_measure.hpp"

namespace lsmbs {

namespace {

std::vector<std::string> xyz(const std::string& name) {
  return {name + ".x", name + ".y", name + ".z"};
}

}  // namespace

// ------------------------------------------------------------------ SpatialPointMeasure
SpatialPointMeasure::SpatialPointMeasure(std::string name, Kind kind, int dof0, const Vec3& d)
    : Measure(std::move(name)), kind_(kind), dof0_(dof0), d_(d) {}

std::vector<std::string> SpatialPointMeasure::components() const { return xyz(name()); }

std::vector<std::string> SpatialPointMeasure::units() const {
  const std::string u = kind_ == Kind::kPosition ? "m" : "m/s";
  return {u, u, u};
}

void SpatialPointMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                                   double* out) const {
  const Vec& x = kind_ == Kind::kPosition ? s.q : s.v;  // x = r + Σ d_k e_k, linear
  Vec3 p = x.segment<3>(dof0_);
  for (int k = 0; k < 3; ++k) p += d_[k] * x.segment<3>(dof0_ + 3 + 3 * k);
  for (int i = 0; i < 3; ++i) out[i] = p[i];
}

void SpatialPointMeasure::gradient(const Model&, const State&, const ModelParams&, int c,
                                   MeasureGradient& g) const {
  auto& row = kind_ == Kind::kPosition ? g.dq : g.dv;
  row.emplace_back(dof0_ + c, 1.0);
  for (int k = 0; k < 3; ++k) row.emplace_back(dof0_ + 3 + 3 * k + c, d_[k]);
}

// ------------------------------------------------------------------ NodeSetMeasure
NodeSetMeasure::NodeSetMeasure(std::string name, std::vector<int> node_dofs)
    : Measure(std::move(name)), dofs_(std::move(node_dofs)) {}

std::vector<std::string> NodeSetMeasure::components() const { return xyz(name()); }

void NodeSetMeasure::evaluate(const Model&, const State& s, const ModelParams&, double* out) const {
  Vec3 x = Vec3::Zero();
  for (int d : dofs_) x += s.q.segment<3>(d);
  x /= static_cast<double>(dofs_.size());
  for (int i = 0; i < 3; ++i) out[i] = x[i];
}

void NodeSetMeasure::gradient(const Model&, const State&, const ModelParams&, int c,
                              MeasureGradient& g) const {
  for (int d : dofs_) g.dq.emplace_back(d + c, 1.0 / static_cast<double>(dofs_.size()));
}

// ------------------------------------------------------------------ SpatialDistanceMeasure
Vec3 SpatialPoint::position(const Vec& q) const {
  if (dof0 < 0) return d;
  Vec3 x = q.segment<3>(dof0);
  for (int k = 0; k < 3; ++k) x += d[k] * q.segment<3>(dof0 + 3 + 3 * k);
  return x;
}

void SpatialDistanceMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                                      double* out) const {
  *out = (b_.position(s.q) - a_.position(s.q)).norm() - ref_;
}

void SpatialDistanceMeasure::gradient(const Model&, const State& s, const ModelParams&, int,
                                      MeasureGradient& g) const {
  const Vec3 u = (b_.position(s.q) - a_.position(s.q)).normalized();
  for (const auto& [pt, sign] : {std::pair{a_, -1.0}, std::pair{b_, 1.0}}) {
    if (pt.dof0 < 0) continue;
    for (int c = 0; c < 3; ++c) {
      g.dq.emplace_back(pt.dof0 + c, sign * u[c]);
      for (int k = 0; k < 3; ++k) g.dq.emplace_back(pt.dof0 + 3 + 3 * k + c, sign * u[c] * pt.d[k]);
    }
  }
}

// ------------------------------------------------------------------ NodeSetDistanceMeasure
NodeSetDistanceMeasure::NodeSetDistanceMeasure(std::string name, std::vector<int> a_dofs,
                                               std::vector<int> b_dofs, double reference)
    : Measure(std::move(name)), a_(std::move(a_dofs)), b_(std::move(b_dofs)), ref_(reference) {}

Vec3 NodeSetDistanceMeasure::span(const Vec& q) const {
  Vec3 xa = Vec3::Zero(), xb = Vec3::Zero();
  for (int d : a_) xa += q.segment<3>(d);
  for (int d : b_) xb += q.segment<3>(d);
  return xb / static_cast<double>(b_.size()) - xa / static_cast<double>(a_.size());
}

void NodeSetDistanceMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                                      double* out) const {
  *out = span(s.q).norm() - ref_;
}

void NodeSetDistanceMeasure::gradient(const Model&, const State& s, const ModelParams&, int,
                                      MeasureGradient& g) const {
  // ∂|d|/∂x̄_b = d/|d| = −∂|d|/∂x̄_a, and ∂x̄/∂x_i = 1/n
  const Vec3 u = span(s.q).normalized();
  for (int d : a_)
    for (int k = 0; k < 3; ++k) g.dq.emplace_back(d + k, -u[k] / static_cast<double>(a_.size()));
  for (int d : b_)
    for (int k = 0; k < 3; ++k) g.dq.emplace_back(d + k, u[k] / static_cast<double>(b_.size()));
}

// ------------------------------------------------------------------ BodyAxisMeasure
BodyAxisMeasure::BodyAxisMeasure(std::string name, int dof0, const Vec3& u)
    : Measure(std::move(name)), dof0_(dof0), u_(u) {}

std::vector<std::string> BodyAxisMeasure::components() const { return xyz(name()); }

void BodyAxisMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                               double* out) const {
  Vec3 w = Vec3::Zero();
  for (int k = 0; k < 3; ++k) w += u_[k] * s.q.segment<3>(dof0_ + 3 + 3 * k);
  for (int i = 0; i < 3; ++i) out[i] = w[i];
}

void BodyAxisMeasure::gradient(const Model&, const State&, const ModelParams&, int c,
                               MeasureGradient& g) const {
  for (int k = 0; k < 3; ++k) g.dq.emplace_back(dof0_ + 3 + 3 * k + c, u_[k]);
}

// ------------------------------------------------------------------ SpatialAngularVelocityMeasure
SpatialAngularVelocityMeasure::SpatialAngularVelocityMeasure(std::string name, int dof0,
                                                             bool body_frame)
    : Measure(std::move(name)), dof0_(dof0), body_(body_frame) {}

std::vector<std::string> SpatialAngularVelocityMeasure::components() const { return xyz(name()); }

void SpatialAngularVelocityMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                                             double* out) const {
  const auto e = [&](int k) -> Vec3 { return s.q.segment<3>(dof0_ + 3 + 3 * k); };
  const auto ed = [&](int k) -> Vec3 { return s.v.segment<3>(dof0_ + 3 + 3 * k); };
  Vec3 w;
  if (body_)
    w = Vec3(e(2).dot(ed(1)), e(0).dot(ed(2)), e(1).dot(ed(0)));
  else
    w = 0.5 * (e(0).cross(ed(0)) + e(1).cross(ed(1)) + e(2).cross(ed(2)));
  for (int i = 0; i < 3; ++i) out[i] = w[i];
}

void SpatialAngularVelocityMeasure::gradient(const Model&, const State& s, const ModelParams&,
                                             int c, MeasureGradient& g) const {
  const int e0 = dof0_ + 3;
  if (body_) {
    // Ω_c = e_a·ė_b with (a, b) = (3, 2), (1, 3), (2, 1) for c = 1, 2, 3 (1-based)
    static const int a_of[3] = {2, 0, 1}, b_of[3] = {1, 2, 0};
    const int a = a_of[c], b = b_of[c];
    for (int i = 0; i < 3; ++i) {
      g.dq.emplace_back(e0 + 3 * a + i, s.v[e0 + 3 * b + i]);
      g.dv.emplace_back(e0 + 3 * b + i, s.q[e0 + 3 * a + i]);
    }
    return;
  }
  // ω_c = ½ Σ_k (e_k × ė_k)_c = ½ Σ_k (e_k,c+1 ė_k,c+2 − e_k,c+2 ė_k,c+1)
  const int i1 = (c + 1) % 3, i2 = (c + 2) % 3;
  for (int k = 0; k < 3; ++k) {
    const int b = e0 + 3 * k;
    g.dq.emplace_back(b + i1, 0.5 * s.v[b + i2]);
    g.dq.emplace_back(b + i2, -0.5 * s.v[b + i1]);
    g.dv.emplace_back(b + i2, 0.5 * s.q[b + i1]);
    g.dv.emplace_back(b + i1, -0.5 * s.q[b + i2]);
  }
}

// ------------------------------------------------------------------ JointTranslationMeasure
JointTranslationMeasure::JointTranslationMeasure(std::string name,
                                                 std::unique_ptr<ConstraintElement> block)
    : Measure(std::move(name)), block_(std::move(block)) {}

LocalVec JointTranslationMeasure::gather(const Vec& q) const {
  const auto d = block_->dofs();
  LocalVec z(static_cast<Eigen::Index>(d.size()));
  for (size_t i = 0; i < d.size(); ++i) z[static_cast<Eigen::Index>(i)] = q[d[i]];
  return z;
}

void JointTranslationMeasure::evaluate(const Model&, const State& s, const ModelParams& p,
                                       double* out) const {
  LocalEqVec phi;
  block_->evaluate(s.t, gather(s.q), p, phi, nullptr);
  out[0] = phi[0];
}

void JointTranslationMeasure::gradient(const Model&, const State& s, const ModelParams& p, int,
                                       MeasureGradient& g) const {
  LocalEqVec phi;
  LocalJac J;
  block_->evaluate(s.t, gather(s.q), p, phi, &J);
  const auto d = block_->dofs();
  for (size_t i = 0; i < d.size(); ++i) {
    const double v = J(0, static_cast<Eigen::Index>(i));
    if (v != 0) g.dq.emplace_back(d[i], v);
  }
}

}  // namespace lsmbs
