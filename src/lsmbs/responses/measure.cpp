#include "lsmbs/responses/measure.hpp"

#include <cmath>

namespace lsmbs {
namespace {
Vec2 point_position(const PointRef& p, const Vec& q) {
  double buf[3] = {0, 0, 0};
  for (int i = 0; i < p.num_dofs(); ++i) buf[i] = q[p.dof0 + i];
  return PointKinematics::position(p, buf);
}
}  // namespace

void PositionMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                               double* out) const {
  const Vec2 x = point_position(pt_, s.q);
  out[0] = x.x();
  out[1] = x.y();
}

namespace {
// ∂p/∂q of a point, row `row` (0: x, 1: y) → sparse entries scaled by w.
void point_row(const PointRef& p, const Vec& q, const Vec2& w,
               std::vector<std::pair<int, double>>& out) {
  if (p.kind == PointRef::Kind::kGround) return;
  out.emplace_back(p.dof0, w.x());
  out.emplace_back(p.dof0 + 1, w.y());
  if (p.kind == PointRef::Kind::kBody)
    out.emplace_back(p.dof0 + 2, w.dot(rotation_derivative(q[p.dof0 + 2]) * p.local));
}
}  // namespace

void PositionMeasure::gradient(const Model&, const State& s, const ModelParams&, int c,
                               MeasureGradient& g) const {
  point_row(pt_, s.q, c == 0 ? Vec2(1, 0) : Vec2(0, 1), g.dq);
}

void VelocityMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                               double* out) const {
  Vec2 v = Vec2::Zero();
  if (pt_.kind != PointRef::Kind::kGround) v = s.v.segment<2>(pt_.dof0);
  if (pt_.kind == PointRef::Kind::kBody)
    v += s.v[pt_.dof0 + 2] * (rotation_derivative(s.q[pt_.dof0 + 2]) * pt_.local);
  out[0] = v.x();
  out[1] = v.y();
}

void VelocityMeasure::gradient(const Model&, const State& s, const ModelParams&, int c,
                               MeasureGradient& g) const {
  const Vec2 w = c == 0 ? Vec2(1, 0) : Vec2(0, 1);
  point_row(pt_, s.q, w, g.dv);  // ∂ṗ/∂q̇ = ∂p/∂q
  if (pt_.kind == PointRef::Kind::kBody) {
    const double th = s.q[pt_.dof0 + 2];  // ∂(θ̇ R′(θ) d)/∂θ = θ̇ R″(θ) d = −θ̇ R(θ) d
    g.dq.emplace_back(pt_.dof0 + 2, -s.v[pt_.dof0 + 2] * w.dot(rotation(th) * pt_.local));
  }
}

void DistanceMeasure::gradient(const Model&, const State& s, const ModelParams&, int,
                               MeasureGradient& g) const {
  const Vec2 d = point_position(b_, s.q) - point_position(a_, s.q);
  const double l = d.norm();
  if (!(l > 0)) return;
  const Vec2 n = d / l;
  point_row(b_, s.q, n, g.dq);
  point_row(a_, s.q, -n, g.dq);
}

void PathDeviationMeasure::gradient(const Model&, const State& s, const ModelParams&, int,
                                    MeasureGradient& g) const {
  const Vec2 e = path_.at(s.t) - point_position(pt_, s.q);
  const double f = e.norm();
  if (!(f > 0)) return;  // not differentiable at zero deviation; take the zero subgradient
  point_row(pt_, s.q, -e / f, g.dq);
}

void KineticEnergyMeasure::gradient(const Model& m, const State& s, const ModelParams& p, int,
                                    MeasureGradient& g) const {
  // ∂T/∂q̇ = M q̇; ∂T/∂q = ½ q̇ᵀ (∂M/∂q) q̇, non-zero only where M depends on q (rigid bodies
  // with an offset centre of mass: by central differences on the element's few DOFs).
  Mat v(m.nq(), 1), z = Mat::Zero(m.nq(), 1), Mv;
  v.col(0) = s.v;
  m.mass_damping_product(s, p, v, z, Mv);
  for (int i = 0; i < m.nq(); ++i)
    if (Mv(i, 0) != 0) g.dv.emplace_back(i, Mv(i, 0));
  for (size_t e = 0; e < m.forces().size(); ++e) {
    const auto& f = m.forces()[e];
    if (!f->mass_depends_on_q()) continue;
    const auto d = f->dofs();
    State x = s;
    for (size_t j = 0; j < d.size(); ++j) {
      const double h = 1e-7;
      auto T_local = [&](double dq) {
        x.q[d[j]] = s.q[d[j]] + dq;
        LocalState ls;
        ls.t = s.t;
        ls.q.resize(d.size()), ls.v.resize(d.size()), ls.a.setZero(d.size());
        for (size_t k = 0; k < d.size(); ++k) ls.q[k] = x.q[d[k]], ls.v[k] = s.v[d[k]];
        LocalVec r = LocalVec::Zero(d.size());
        LocalMat M = LocalMat::Zero(d.size(), d.size());
        const Coefficients cm{1, 0, 0};
        f->evaluate(ls, p, r, &cm, &M);
        return 0.5 * ls.v.dot(M * ls.v);
      };
      const double dT = (T_local(h) - T_local(-h)) / (2 * h);
      x.q[d[j]] = s.q[d[j]];
      if (dT != 0) g.dq.emplace_back(d[j], dT);
    }
  }
}

void StrainEnergyMeasure::gradient(const Model& m, const State& s, const ModelParams& p, int,
                                   MeasureGradient& g) const {
  // ∂W/∂q = f_int of the flexible bodies
  for (const auto& b : m.flexible_bodies()) {
    const double t = p.scalars[b->thickness_param], nu = p.scalars[b->nu_param],
                 E0 = p.scalars[b->E_param];
    for (int e = 0; e < b->mesh.num_elements(); ++e) {
      QuadElement::Vec8 x, f;
      for (int i = 0; i < 4; ++i)
        x.segment<2>(2 * i) = s.q.segment<2>(b->node_dof(b->mesh.quads[e][i]));
      b->elements[e].internal_force(x, p.fields[b->field][e] * E0, nu, t, f, nullptr);
      for (int i = 0; i < 4; ++i) {
        g.dq.emplace_back(b->node_dof(b->mesh.quads[e][i]), f[2 * i]);
        g.dq.emplace_back(b->node_dof(b->mesh.quads[e][i]) + 1, f[2 * i + 1]);
      }
    }
  }
}

void DistanceMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                               double* out) const {
  *out = (point_position(b_, s.q) - point_position(a_, s.q)).norm() - ref_;
}

Vec2 ChainPath::at(double t) const {
  Vec2 x = origin;
  double phi = 0;
  for (const auto& l : links) {
    phi = (l.relative ? phi : 0.0) + l.law->value(t);
    x += l.length * Vec2(std::cos(phi), std::sin(phi));
  }
  return x;
}

void PathDeviationMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                                    double* out) const {
  *out = (path_.at(s.t) - point_position(pt_, s.q)).norm();
}

std::vector<std::string> ConstraintForceMeasure::components() const {
  std::vector<std::string> c;
  for (size_t i = 0; i < rows_.size(); ++i) c.push_back(name() + "." + std::to_string(i));
  return c;
}

std::vector<std::string> ConstraintForceMeasure::units() const {
  std::vector<std::string> u;
  for (size_t i = 0; i < rows_.size(); ++i) u.push_back(angular_[i] ? "N*m" : "N");
  return u;
}

void ConstraintForceMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                                      double* out) const {
  for (size_t i = 0; i < rows_.size(); ++i) out[i] = k_ * s.lambda[rows_[i]];
}

}  // namespace lsmbs
