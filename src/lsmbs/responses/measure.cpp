#include "lsmbs/responses/measure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lsmbs/fem/solid_stress.hpp"

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

namespace {
// The frame of a rigid-body point: its origin o and the body's rotation R(θ).
struct Frame {
  Vec2 o;
  Mat2 R, dR;  // R(θ), R′(θ)
  double theta;
};
Frame frame_at(const PointRef& f, const Vec& q) {
  const double th = q[f.dof0 + 2];
  return {point_position(f, q), rotation(th), rotation_derivative(th), th};
}
// J: the rotation by +90°, J (x, y) = (−y, x)
Vec2 perp(const Vec2& v) { return Vec2(-v.y(), v.x()); }
// ∂r_c/∂q · w added to `out`, r = Rᵀ (p − o): through p (Rᵀ ∂p/∂q), through o (−Rᵀ ∂o/∂q) and
// through θ (R′ᵀ (p − o)).
void frame_position_rows(const PointRef& pt, const PointRef& frame, const Vec& q, int c, double w,
                         std::vector<std::pair<int, double>>& out) {
  const Frame F = frame_at(frame, q);
  const Vec2 d = point_position(pt, q) - F.o;
  point_row(pt, q, w * F.R.col(c), out);
  point_row(frame, q, -w * F.R.col(c), out);
  out.emplace_back(frame.dof0 + 2, w * F.dR.col(c).dot(d));
}
// ṗ of a point (VelocityMeasure).
Vec2 point_velocity(const PointRef& pt, const State& s) {
  Vec2 v = Vec2::Zero();
  if (pt.kind != PointRef::Kind::kGround) v = s.v.segment<2>(pt.dof0);
  if (pt.kind == PointRef::Kind::kBody)
    v += s.v[pt.dof0 + 2] * (rotation_derivative(s.q[pt.dof0 + 2]) * pt.local);
  return v;
}
// ∂(w · ṗ)/∂q of a point: a body point's ṗ depends on θ (∂(θ̇ R′ d)/∂θ = −θ̇ R d).
void velocity_q_row(const PointRef& pt, const State& s, const Vec2& w,
                    std::vector<std::pair<int, double>>& out) {
  if (pt.kind != PointRef::Kind::kBody) return;
  out.emplace_back(pt.dof0 + 2, -s.v[pt.dof0 + 2] * w.dot(rotation(s.q[pt.dof0 + 2]) * pt.local));
}
}  // namespace

void FramePositionMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                                    double* out) const {
  const Frame F = frame_at(frame_, s.q);
  const Vec2 r = F.R.transpose() * (point_position(pt_, s.q) - F.o);
  out[0] = r.x();
  out[1] = r.y();
}

void FramePositionMeasure::gradient(const Model&, const State& s, const ModelParams&, int c,
                                    MeasureGradient& g) const {
  frame_position_rows(pt_, frame_, s.q, c, 1.0, g.dq);
}

void FrameVelocityMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                                    double* out) const {
  const Frame F = frame_at(frame_, s.q);
  const Vec2 r = F.R.transpose() * (point_position(pt_, s.q) - F.o);
  const double w = s.v[frame_.dof0 + 2];
  const Vec2 rd =
      F.R.transpose() * (point_velocity(pt_, s) - point_velocity(frame_, s)) - w * perp(r);
  out[0] = rd.x();
  out[1] = rd.y();
}

void FrameVelocityMeasure::gradient(const Model&, const State& s, const ModelParams&, int c,
                                    MeasureGradient& g) const {
  // ṙ_c = R_c · (ṗ − ȯ) − θ̇ (J r)_c, R_c the c-th column of R; (J r)_0 = −r_1, (J r)_1 = r_0
  const Frame F = frame_at(frame_, s.q);
  const Vec2 Rc = F.R.col(c);
  const double w = s.v[frame_.dof0 + 2];
  // velocities: ∂ṗ/∂q̇ = ∂p/∂q, and θ̇ of the frame in −θ̇ (J r)_c
  point_row(pt_, s.q, Rc, g.dv);
  point_row(frame_, s.q, -Rc, g.dv);
  const Vec2 r = F.R.transpose() * (point_position(pt_, s.q) - F.o);
  g.dv.emplace_back(frame_.dof0 + 2, -perp(r)[c]);
  // positions: ṗ and ȯ through the bodies' angles, R_c through θ, r in −θ̇ (J r)_c
  velocity_q_row(pt_, s, Rc, g.dq);
  velocity_q_row(frame_, s, -Rc, g.dq);
  g.dq.emplace_back(frame_.dof0 + 2,
                    F.dR.col(c).dot(point_velocity(pt_, s) - point_velocity(frame_, s)));
  if (c == 0)
    frame_position_rows(pt_, frame_, s.q, 1, w, g.dq);  // −θ̇ (−r_1)
  else
    frame_position_rows(pt_, frame_, s.q, 0, -w, g.dq);  // −θ̇ r_0
}

void LineDistanceMeasure::evaluate(const Model&, const State& s, const ModelParams&,
                                   double* out) const {
  const Vec2 a = point_position(a_, s.q), u = point_position(b_, s.q) - a,
             w = point_position(pt_, s.q) - a;
  const double L = u.norm();
  *out = L > 0 ? (u.x() * w.y() - u.y() * w.x()) / L : std::numeric_limits<double>::quiet_NaN();
}

void LineDistanceMeasure::gradient(const Model&, const State& s, const ModelParams&, int,
                                   MeasureGradient& g) const {
  // f = (u × w)/L, u = b − a, w = p − a: ∂f/∂w = J u / L, ∂f/∂u = −J w / L − f u / L²,
  // ∂f/∂a = −∂f/∂u − ∂f/∂w
  const Vec2 a = point_position(a_, s.q), u = point_position(b_, s.q) - a,
             w = point_position(pt_, s.q) - a;
  const double L = u.norm();
  if (!(L > 0)) return;
  const double f = (u.x() * w.y() - u.y() * w.x()) / L;
  const Vec2 dw = perp(u) / L, du = -perp(w) / L - f * u / (L * L);
  point_row(pt_, s.q, dw, g.dq);
  point_row(b_, s.q, du, g.dq);
  point_row(a_, s.q, -du - dw, g.dq);
}

void CombinationMeasure::evaluate(const Model& m, const State& s, const ModelParams& p,
                                  double* out) const {
  double v = constant_;
  std::vector<double> buf;
  for (const auto& t : terms_) {
    buf.resize(t.measure->components().size());
    t.measure->evaluate(m, s, p, buf.data());
    v += t.weight * buf[static_cast<size_t>(t.component)];
  }
  *out = v;
}

void CombinationMeasure::gradient(const Model& m, const State& s, const ModelParams& p, int,
                                  MeasureGradient& g) const {
  MeasureGradient part;
  auto add = [](const std::vector<std::pair<int, double>>& from, double w,
                std::vector<std::pair<int, double>>& to) {
    for (const auto& [j, v] : from) to.emplace_back(j, w * v);
  };
  for (const auto& t : terms_) {
    part.clear();
    t.measure->gradient(m, s, p, t.component, part);
    add(part.dq, t.weight, g.dq);
    add(part.dv, t.weight, g.dv);
    add(part.da, t.weight, g.da);
    add(part.dl, t.weight, g.dl);
  }
}

bool CombinationMeasure::depends_on_params() const {
  return std::any_of(terms_.begin(), terms_.end(),
                     [](const Term& t) { return t.measure->depends_on_params(); });
}

bool CombinationMeasure::state_independent() const {
  return std::all_of(terms_.begin(), terms_.end(),
                     [](const Term& t) { return t.measure->state_independent(); });
}

bool CombinationMeasure::field_partials(const Model& m, const State& s, const ModelParams& p, int,
                                        int& field, Vec& df_dmu) const {
  // the terms with exact ∂f/∂μ (the loader lets them combine only with terms that do not depend
  // on the parameters, so the sum is exact): Σ w_i ∂f_i/∂μ of one field
  bool any = false;
  Vec part;
  for (const auto& t : terms_) {
    int f = -1;
    if (!t.measure->depends_on_params() ||
        !t.measure->field_partials(m, s, p, t.component, f, part))
      continue;
    if (!any) {
      field = f;
      df_dmu = t.weight * part;
      any = true;
    } else if (f == field) {
      df_dmu += t.weight * part;
    } else {
      return false;  // two fields: refused by the loader
    }
  }
  return any;
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
  // ∂W/∂q = f_int of the flexible and solid bodies
  for (const auto& b : m.flexible_bodies()) {
    const double t = p.scalars[b->thickness_param], nu = p.scalars[b->nu_param],
                 E0 = p.scalars[b->E_param];
    double x[kMaxLocalDofs], f[kMaxLocalDofs];
    for (int e = 0; e < b->mesh.num_elements(); ++e) {
      const int nd = b->element_coordinates(e, s.q, x);
      b->elements[e]->internal_force(x, p.fields[b->field][e] * E0, nu, t, f, nullptr);
      for (int k = 0; k < nd; ++k) g.dq.emplace_back(b->element_dof(e, k), f[k]);
    }
  }
  for (const auto& b : m.solid_bodies()) {
    double x[kMaxLocalDofs], f[kMaxLocalDofs];
    for (int e = 0; e < b->mesh.num_elements(); ++e) {
      const int nd = b->element_coordinates(e, s.q, x);
      b->elements[static_cast<size_t>(e)]->internal_force(x, b->element_E(e, p), b->nu(p), f,
                                                          nullptr);
      const auto& cell = b->mesh.cells[static_cast<size_t>(e)];
      for (int k = 0; k < nd; ++k) g.dq.emplace_back(b->node_dof(cell[k / 3]) + k % 3, f[k]);
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

void ConstraintForceMeasure::evaluate_scaled(const Model&, const State& s, const ModelParams&,
                                             double k, double* out) const {
  for (size_t i = 0; i < rows_.size(); ++i) out[i] = k * s.lambda[rows_[i]];
}

}  // namespace lsmbs

namespace lsmbs {
namespace {
double relaxed(double mu, double q) { return mu > 0 ? std::pow(mu, q) : 0.0; }
}  // namespace

std::vector<double> StressMeasure::element_centre(int e) const {
  if (body_) {
    const Vec2 c = body_->mesh.centroid(e);
    return {c.x(), c.y()};
  }
  Vec3 c = Vec3::Zero();
  const auto& cell = solid_->mesh.cells[static_cast<size_t>(e)];
  for (int k : cell) c += solid_->mesh.nodes[static_cast<size_t>(k)];
  c /= static_cast<double>(cell.size());
  return {c.x(), c.y(), c.z()};
}

void StressMeasure::solid_coordinates(int e, const Vec& q, double* x) const {
  const auto& cell = solid_->mesh.cells[static_cast<size_t>(e)];
  for (size_t k = 0; k < cell.size(); ++k)
    for (int i = 0; i < 3; ++i)
      x[3 * k + static_cast<size_t>(i)] = q[solid_->node_dof(cell[k]) + i];
}

void StressMeasure::element_stresses(const State& s, const ModelParams& p,
                                     std::vector<double>& out) const {
  const Vec& mu = p.fields[field()];
  double x[kMaxLocalDofs];
  if (solid_) {
    const SolidBody& b = *solid_;
    const double E0 = p.scalars[b.E_param], nu = p.scalars[b.nu_param];
    out.resize(b.elements.size());
    for (size_t e = 0; e < b.elements.size(); ++e) {
      solid_coordinates(static_cast<int>(e), s.q, x);
      out[e] = relaxed(mu[static_cast<Eigen::Index>(e)], o_.relaxation) *
               solid_centre_von_mises(*b.elements[e], x, E0, nu);
    }
    return;
  }
  const FlexibleBody& b = *body_;
  const int ne = static_cast<int>(b.elements.size());
  const double E0 = p.scalars[b.E_param], nu = p.scalars[b.nu_param];
  out.resize(ne);
  for (int e = 0; e < ne; ++e) {
    b.element_coordinates(e, s.q, x);
    out[e] = relaxed(mu[e], o_.relaxation) * b.elements[e]->centre_stress(x, E0, nu, false).vm;
  }
}

double StressMeasure::aggregate(const std::vector<double>& s, std::vector<double>* w) const {
  const size_t n = s.size();
  if (w) w->assign(n, 0.0);
  if (n == 0) return 0;
  const double smax = *std::max_element(s.begin(), s.end());
  if (o_.aggregation == Aggregation::kKs) {
    const double rho = o_.parameter, ref = o_.reference, m = smax / ref;
    double sum = 0;
    if (std::isfinite(m) && (m == 0 || std::isnormal(m))) {  // the normalized stresses are doubles
      for (double v : s) sum += std::exp(rho * (v / ref - m));
      if (w)
        for (size_t e = 0; e < n; ++e) (*w)[e] = std::exp(rho * (s[e] / ref - m)) / sum;
      return ref * (m + std::log(sum) / rho);
    }
    // A reference so far below the stresses that s/σ_ref overflows (σ_ref = 1e-300: every
    // element above 1.8e8 Pa became inf, inf − inf = NaN, and a response's max over the steps
    // skipped those steps), or so far above that it underflows: the same sum in stress units,
    // shifted by the maximum, f = s_max + σ_ref ln Σ_e exp(−ρ (s_max − s_e)/σ_ref) / ρ. Every
    // term is in [0, 1] and the maximum's is 1 (no NaN, ln Σ ≥ 0), so max ≤ f ≤ max + σ_ref ln N/ρ.
    for (double v : s) sum += std::exp(-rho * ((smax - v) / ref));
    if (w)
      for (size_t e = 0; e < n; ++e) (*w)[e] = std::exp(-rho * ((smax - s[e]) / ref)) / sum;
    const double lse = std::log(sum);
    return lse > 0 ? smax + ref * (lse / rho) : smax;
  }
  if (smax <= 0) return 0;  // every element unstressed: f = 0, subgradient 0
  const double P = o_.parameter;
  double sum = 0;
  for (double v : s) sum += std::pow(v / smax, P);
  const double f = smax * std::pow(sum, 1 / P);
  if (w)
    for (size_t e = 0; e < n; ++e) (*w)[e] = std::pow(s[e] / f, P - 1);
  return f;
}

void StressMeasure::evaluate(const Model&, const State& s, const ModelParams& p,
                             double* out) const {
  thread_local std::vector<double> se;
  element_stresses(s, p, se);
  *out = aggregate(se, nullptr);
}

void StressMeasure::gradient(const Model&, const State& s, const ModelParams& p, int,
                             MeasureGradient& g) const {
  thread_local std::vector<double> se, w;
  thread_local Vec dq;
  element_stresses(s, p, se);
  aggregate(se, &w);
  const Vec& mu = p.fields[field()];
  double x[kMaxLocalDofs], d[kMaxLocalDofs];
  if (solid_) {
    const SolidBody& b = *solid_;
    const double E0 = p.scalars[b.E_param], nu = p.scalars[b.nu_param];
    dq.setZero(3 * b.mesh.num_nodes());
    for (int e = 0; e < static_cast<int>(se.size()); ++e) {
      if (w[e] == 0) continue;
      solid_coordinates(e, s.q, x);
      solid_centre_von_mises(*b.elements[static_cast<size_t>(e)], x, E0, nu, d);
      const double f = w[e] * relaxed(mu[e], o_.relaxation);
      const auto& cell = b.mesh.cells[static_cast<size_t>(e)];
      for (size_t k = 0; k < 3 * cell.size(); ++k) dq[3 * cell[k / 3] + k % 3] += f * d[k];
    }
    for (int i = 0; i < dq.size(); ++i)
      if (dq[i] != 0) g.dq.emplace_back(b.dof0 + i, dq[i]);
    return;
  }
  const FlexibleBody& b = *body_;
  const double E0 = p.scalars[b.E_param], nu = p.scalars[b.nu_param];
  const int nn = b.mesh.num_nodes();
  dq.setZero(2 * nn);
  for (int e = 0; e < static_cast<int>(se.size()); ++e) {
    if (w[e] == 0) continue;
    const int nd = b.element_coordinates(e, s.q, x);
    const PointStress cs = b.elements[e]->centre_stress(x, E0, nu, true);
    const double f = w[e] * relaxed(mu[e], o_.relaxation);
    const Cell& cell = b.mesh.cells[static_cast<size_t>(e)];
    for (int k = 0; k < nd; ++k) dq[2 * cell[k / 2] + k % 2] += f * cs.dvm[k];
  }
  for (int i = 0; i < 2 * nn; ++i)
    if (dq[i] != 0) g.dq.emplace_back(b.dof0 + i, dq[i]);
}

bool StressMeasure::field_partials(const Model&, const State& s, const ModelParams& p, int,
                                   int& field, Vec& df_dmu) const {
  thread_local std::vector<double> se, w;
  element_stresses(s, p, se);
  aggregate(se, &w);
  const Vec& mu = p.fields[this->field()];
  field = this->field();
  df_dmu.setZero(static_cast<Eigen::Index>(se.size()));
  const double q = o_.relaxation;
  // s_e = μ_e^q σ_vm,e: ∂s_e/∂μ_e = q s_e / μ_e
  for (size_t e = 0; e < se.size(); ++e)
    if (mu[e] > 0) df_dmu[static_cast<Eigen::Index>(e)] = w[e] * q * se[e] / mu[e];
  return true;
}

}  // namespace lsmbs
