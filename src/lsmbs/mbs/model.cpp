#include "lsmbs/mbs/model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "lsmbs/core/error.hpp"
#include "lsmbs/fem/element_types.hpp"

namespace lsmbs {

int Model::add_parameter(const std::string& name, double value) {
  if (parameter_index(name) >= 0) throw Error("duplicate parameter name '" + name + "'");
  param_names_.push_back(name);
  params_.scalars.push_back(value);
  return static_cast<int>(param_names_.size()) - 1;
}

int Model::parameter_index(const std::string& name) const {
  for (size_t i = 0; i < param_names_.size(); ++i)
    if (param_names_[i] == name) return static_cast<int>(i);
  return -1;
}

int Model::add_field(Vec values) {
  params_.fields.push_back(std::move(values));
  return static_cast<int>(params_.fields.size()) - 1;
}

int Model::add_dofs(int n, const std::string& owner) {
  if (finalized_) throw std::logic_error("Model::add_dofs after finalize");
  const int first = nq_;
  nq_ += n;
  dof_owner_.resize(nq_, owner);
  q_init_.conservativeResize(nq_);
  q_init_.tail(n).setZero();
  return first;
}

RigidBody& Model::add_rigid_body(RigidBody b) {
  b.dof0 = add_dofs(3, "rigid body '" + b.name + "'");
  q_init_.segment<3>(b.dof0) << b.position0.x(), b.position0.y(), b.angle0;
  rigid_.push_back(std::move(b));
  return rigid_.back();
}

void Model::add_attachment(const PointRef& p) {
  if (p.kind != PointRef::Kind::kBody) return;
  for (auto& b : rigid_)
    if (b.dof0 == p.dof0) {
      if (std::find(b.attachments.begin(), b.attachments.end(), p.local) == b.attachments.end())
        b.attachments.push_back(p.local);
      return;
    }
}

FlexibleBody& Model::add_flexible_body(FlexibleBody b) {
  auto body = std::make_unique<FlexibleBody>(std::move(b));
  body->dof0 = add_dofs(2 * body->mesh.num_nodes(), "flexible body '" + body->name + "'");
  for (int i = 0; i < body->mesh.num_nodes(); ++i)
    q_init_.segment<2>(body->node_dof(i)) = body->placed(i);
  body->elements.clear();
  body->elements.reserve(body->mesh.num_elements());
  for (int e = 0; e < body->mesh.num_elements(); ++e) {
    const ElementType& type = element_type(body->mesh.cells[static_cast<size_t>(e)].type);
    try {
      body->elements.push_back(type.make(body->mesh.cell_nodes(e).data(), body->element_options));
    } catch (const Error& err) {
      throw Error("flexible body '" + body->name + "', element " + std::to_string(e) + ": " +
                  err.what());
    }
  }
  if (body->field < 0) body->field = add_field(Vec::Ones(body->mesh.num_elements()));
  flex_.push_back(std::move(body));
  FlexibleBody* fb = flex_.back().get();
  fb->first_force = static_cast<int>(forces_.size());
  for (int e = 0; e < fb->mesh.num_elements(); ++e) add_force(std::make_unique<PlaneForce>(fb, e));
  length_scale_ = std::max(length_scale_ == 1 ? 0.0 : length_scale_, fb->mesh.size());
  return *fb;
}

void Model::add_force(std::unique_ptr<ForceElement> f) {
  if (finalized_) throw std::logic_error("Model::add_force after finalize");
  if (f->dofs().size() > static_cast<size_t>(kMaxLocalDofs))
    throw std::logic_error("force element too large");
  forces_.push_back(std::move(f));
}

void Model::add_constraint(std::unique_ptr<ConstraintElement> c) {
  if (finalized_) throw std::logic_error("Model::add_constraint after finalize");
  if (c->dofs().size() > static_cast<size_t>(kMaxLocalDofs) || c->size() > kMaxLocalEqs)
    throw std::logic_error("constraint element too large");
  cons_.push_back(std::move(c));
}

SolidBody& Model::add_solid_body(SolidBody b) {
  auto body = std::make_unique<SolidBody>(std::move(b));
  body->dof0 = add_dofs(3 * body->mesh.num_nodes(), "solid body '" + body->name + "'");
  for (int i = 0; i < body->mesh.num_nodes(); ++i)
    q_init_.segment<3>(body->node_dof(i)) = body->mesh.nodes[static_cast<size_t>(i)];
  body->elements.clear();
  for (int e = 0; e < body->mesh.num_elements(); ++e) {
    const auto& c = body->mesh.cells[static_cast<size_t>(e)];
    try {
      if (c.size() == 8) {
        std::array<Vec3, 8> X;
        for (size_t k = 0; k < 8; ++k) X[k] = body->mesh.nodes[static_cast<size_t>(c[k])];
        body->elements.push_back(std::make_unique<HexElement>(X, body->formulation));
      } else if (c.size() == 4) {
        std::array<Vec3, 4> X;
        for (size_t k = 0; k < 4; ++k) X[k] = body->mesh.nodes[static_cast<size_t>(c[k])];
        body->elements.push_back(std::make_unique<TetElement>(X));
      } else {
        throw Error("a cell of " + std::to_string(c.size()) +
                    " nodes (8: hexahedron, 4: tetrahedron)");
      }
    } catch (const Error& err) {
      throw Error("solid body '" + body->name + "', element " + std::to_string(e) + ": " +
                  err.what());
    }
  }
  if (body->field < 0) body->field = add_field(Vec::Ones(body->mesh.num_elements()));
  solid_.push_back(std::move(body));
  SolidBody* sb = solid_.back().get();
  sb->first_force = static_cast<int>(forces_.size());
  for (int e = 0; e < sb->mesh.num_elements(); ++e) add_force(std::make_unique<SolidForce>(sb, e));
  length_scale_ = std::max(length_scale_ == 1 ? 0.0 : length_scale_, sb->mesh.size());
  return *sb;
}

const SolidBody* Model::find_solid(const std::string& name) const {
  for (const auto& b : solid_)
    if (b->name == name) return b.get();
  return nullptr;
}

SpatialRigidBody& Model::add_spatial_body(SpatialRigidBody b) {
  b.dof0 = add_dofs(12, "spatial body '" + b.name + "'");
  q_init_.segment<3>(b.dof0) = b.position0;
  for (int k = 0; k < 3; ++k) q_init_.segment<3>(b.dof0 + 3 + 3 * k) = b.orientation0.col(k);
  spatial_.push_back(std::move(b));
  return spatial_.back();
}

void Model::add_spatial_attachment(int dof0, const Vec3& d) {
  for (auto& b : spatial_)
    if (b.dof0 == dof0) {
      for (const auto& a : b.attachments)
        if ((a - d).norm() <= 1e-12 * (1 + d.norm())) return;
      b.attachments.push_back(d);
    }
}

const SpatialRigidBody* Model::find_spatial(const std::string& name) const {
  for (const auto& b : spatial_)
    if (b.name == name) return &b;
  return nullptr;
}

const RigidBody* Model::find_rigid(const std::string& name) const {
  for (const auto& b : rigid_)
    if (b.name == name) return &b;
  return nullptr;
}

const FlexibleBody* Model::find_flexible(const std::string& name) const {
  for (const auto& b : flex_)
    if (b->name == name) return b.get();
  return nullptr;
}

void Model::finalize() {
  if (finalized_) return;
  nc_ = 0;
  eq_offset_.clear();
  for (const auto& c : cons_) {
    eq_offset_.push_back(nc_);
    nc_ += c->size();
  }
  SparsityBuilder sb(n());
  for (const auto& f : forces_) force_block_.push_back(sb.add_block(f->dofs(), f->dofs()));
  for (size_t i = 0; i < cons_.size(); ++i) {
    std::vector<int> rows(cons_[i]->size());
    for (int k = 0; k < cons_[i]->size(); ++k) rows[k] = nq_ + eq_offset_[i] + k;
    con_block_qq_.push_back(sb.add_block(cons_[i]->dofs(), cons_[i]->dofs()));
    con_block_ql_.push_back(sb.add_block(cons_[i]->dofs(), rows));
    con_block_lq_.push_back(sb.add_block(rows, cons_[i]->dofs()));
    con_rows_.push_back(std::move(rows));
  }
  sb.add_diagonal();
  asm_ = BlockAssembler(sb.finalize());
  // Length scale: spread of the initial positions of all points.
  if (nq_ > 0) {
    Vec2 lo = Vec2::Constant(1e300), hi = Vec2::Constant(-1e300);
    for (const auto& b : rigid_) {
      lo = lo.cwiseMin(b.position0);
      hi = hi.cwiseMax(b.position0);
    }
    for (const auto& b : flex_)
      for (int i = 0; i < b->mesh.num_nodes(); ++i) {
        lo = lo.cwiseMin(b->placed(i));
        hi = hi.cwiseMax(b->placed(i));
      }
    double d = (hi - lo).norm();
    if (!spatial_.empty()) {  // spatial bodies: the spread of their centres of mass in 3D
      Vec3 lo3 = Vec3::Constant(1e300), hi3 = Vec3::Constant(-1e300);
      for (const auto& b : spatial_) {
        lo3 = lo3.cwiseMin(b.position0);
        hi3 = hi3.cwiseMax(b.position0);
      }
      const double d3 = (hi3 - lo3).norm();
      d = std::isfinite(d) ? std::max(d, d3) : d3;
    }
    length_scale_ = d > 0 && std::isfinite(d) ? d : 1.0;
  }
  finalized_ = true;
}

std::string Model::why_no_pivot(int i, const ModelParams& p) const {
  for (const auto& b : spatial_)
    if (i >= b.dof0 + 3 && i < b.dof0 + 12) {
      const auto moment = [&](int k) {
        const int ip = b.inertia_params[static_cast<size_t>(k)];
        return ip >= 0 ? p.scalars[static_cast<size_t>(ip)] : 0.0;
      };
      std::ostringstream o;
      o << " has no rotational inertia about an axis that its joints leave free (principal "
           "moments I1, I2, I3 = "
        << moment(0) << ", " << moment(1) << ", " << moment(2)
        << " kg m²): give the body its moments, or a joint that fixes that rotation";
      return o.str();
    }
  return " has no mass and is not fixed by a constraint";
}

std::string Model::describe_unknown(int i) const {
  if (i < 0) return "unknown";
  if (i < nq_) {
    for (const auto& b : flex_)
      if (i >= b->dof0 && i < b->dof0 + 2 * b->mesh.num_nodes()) {
        const int node = (i - b->dof0) / 2;
        return "flexible body '" + b->name + "', node " + std::to_string(node) +
               ((i - b->dof0) % 2 ? " (y)" : " (x)");
      }
    for (const auto& b : rigid_)
      if (i >= b.dof0 && i < b.dof0 + 3)
        return "rigid body '" + b.name + "' (" +
               std::string(i - b.dof0 == 0   ? "x"
                           : i - b.dof0 == 1 ? "y"
                                             : "θ") +
               ")";
    for (const auto& b : solid_)
      if (i >= b->dof0 && i < b->dof0 + 3 * b->mesh.num_nodes())
        return "solid body '" + b->name + "', node " + std::to_string((i - b->dof0) / 3) + " (" +
               "xyz"[(i - b->dof0) % 3] + ")";
    for (const auto& b : spatial_)
      if (i >= b.dof0 && i < b.dof0 + 12) {
        static const char* const kCoord[] = {"r", "e1", "e2", "e3"};
        const int k = i - b.dof0;
        return "spatial body '" + b.name + "' (" + kCoord[k / 3] + "." + "xyz"[k % 3] + ")";
      }
    return dof_owner_[i];
  }
  const int row = i - nq_;
  for (size_t c = 0; c < cons_.size(); ++c)
    if (row >= eq_offset_[c] && row < eq_offset_[c] + cons_[c]->size()) {
      // numbered within the joint: its blocks (consecutive elements of one name) count together
      int first = eq_offset_[c];
      for (size_t k = c; k-- > 0 && cons_[k]->name() == cons_[c]->name();) first = eq_offset_[k];
      return "constraint '" + cons_[c]->name() + "' (equation " + std::to_string(row - first) + ")";
    }
  return "constraint row " + std::to_string(row);
}

namespace {
inline void gather(const Vec& g, std::span<const int> dofs, LocalVec& out) {
  out.resize(static_cast<Eigen::Index>(dofs.size()));
  for (size_t i = 0; i < dofs.size(); ++i) out[i] = g[dofs[i]];
}
}  // namespace

void Model::residual(const State& s, const ModelParams& p, double k, double zeta, Vec& R,
                     Vec* absr) const {
  R.setZero(n());
  if (absr) absr->setZero(nq_);
  LocalState ls;
  ls.t = s.t;
  LocalVec r;
  for (const auto& f : forces_) {
    const auto d = f->dofs();
    gather(s.q, d, ls.q);
    gather(s.v, d, ls.v);
    gather(s.a, d, ls.a);
    r.setZero(static_cast<Eigen::Index>(d.size()));
    f->evaluate(ls, p, r, nullptr, nullptr);
    for (size_t i = 0; i < d.size(); ++i) {
      R[d[i]] += r[i];
      if (absr) (*absr)[d[i]] += std::abs(r[i]);
    }
  }
  LocalEqVec phi, mult;
  LocalJac J;
  LocalVec ql;
  for (size_t c = 0; c < cons_.size(); ++c) {
    const auto d = cons_[c]->dofs();
    gather(s.q, d, ql);
    cons_[c]->evaluate(s.t, ql, p, phi, &J);
    const int m = cons_[c]->size();
    mult.resize(m);
    for (int i = 0; i < m; ++i) {
      mult[i] = k * s.lambda[eq_offset_[c] + i] + zeta * phi[i];
      R[nq_ + eq_offset_[c] + i] = k * phi[i];
    }
    for (size_t j = 0; j < d.size(); ++j) {
      double v = 0;
      for (int i = 0; i < m; ++i) v += J(i, j) * mult[i];
      R[d[j]] += v;
      if (absr) (*absr)[d[j]] += std::abs(v);
    }
  }
}

void Model::iteration_matrix(const State& s, const ModelParams& p, const Coefficients& c, double k,
                             double zeta, std::vector<double>& values) const {
  values.assign(asm_.pattern().nnz(), 0.0);
  std::span<double> vals(values);
  LocalState ls;
  ls.t = s.t;
  LocalVec r;
  LocalMat S;
  for (size_t e = 0; e < forces_.size(); ++e) {
    const auto d = forces_[e]->dofs();
    const auto nd = static_cast<Eigen::Index>(d.size());
    gather(s.q, d, ls.q);
    gather(s.v, d, ls.v);
    gather(s.a, d, ls.a);
    r.setZero(nd);
    S.setZero(nd, nd);
    forces_[e]->evaluate(ls, p, r, &c, &S);
    asm_.add(vals, force_block_[e], S);
  }
  LocalEqVec phi, mult;
  LocalJac J;
  LocalVec ql;
  LocalMat H;
  for (size_t ci = 0; ci < cons_.size(); ++ci) {
    const auto d = cons_[ci]->dofs();
    gather(s.q, d, ql);
    cons_[ci]->evaluate(s.t, ql, p, phi, &J);
    const int m = cons_[ci]->size();
    mult.resize(m);
    for (int i = 0; i < m; ++i) mult[i] = k * s.lambda[eq_offset_[ci] + i] + zeta * phi[i];
    if (c.cq != 0) {
      cons_[ci]->hessian(s.t, ql, mult, H);
      H.noalias() += zeta * J.transpose() * J;
      asm_.add(vals, con_block_qq_[ci], H, c.cq);
    }
    asm_.add(vals, con_block_ql_[ci], J.transpose(), k);
    asm_.add(vals, con_block_lq_[ci], J, k);
  }
}

void Model::constraints(double t, const Vec& q, const ModelParams& p, Vec& phi) const {
  phi.setZero(nc_);
  LocalEqVec ph;
  LocalVec ql;
  for (size_t c = 0; c < cons_.size(); ++c) {
    gather(q, cons_[c]->dofs(), ql);
    cons_[c]->evaluate(t, ql, p, ph, nullptr);
    phi.segment(eq_offset_[c], cons_[c]->size()) = ph;
  }
}

SpMat Model::constraint_jacobian(double t, const Vec& q, const ModelParams& p) const {
  std::vector<Eigen::Triplet<double>> trip;
  LocalEqVec ph;
  LocalJac J;
  LocalVec ql;
  for (size_t c = 0; c < cons_.size(); ++c) {
    const auto d = cons_[c]->dofs();
    gather(q, d, ql);
    cons_[c]->evaluate(t, ql, p, ph, &J);
    for (int i = 0; i < cons_[c]->size(); ++i)
      for (size_t j = 0; j < d.size(); ++j)
        if (J(i, j) != 0) trip.emplace_back(eq_offset_[c] + i, d[j], J(i, j));
  }
  SpMat m(nc_, nq_);
  m.setFromTriplets(trip.begin(), trip.end());
  return m;
}

void Model::constraint_jacobian_products(double t, const Vec& q, const ModelParams& p, const Vec& x,
                                         const Vec& y, Vec& Jx, Vec& Jty) const {
  Jx.setZero(nc_);
  Jty.setZero(nq_);
  LocalEqVec ph;
  LocalJac J;
  LocalVec ql;
  for (size_t c = 0; c < cons_.size(); ++c) {
    const auto d = cons_[c]->dofs();
    gather(q, d, ql);
    cons_[c]->evaluate(t, ql, p, ph, &J);
    const int o = eq_offset_[c];
    for (int i = 0; i < cons_[c]->size(); ++i)
      for (size_t j = 0; j < d.size(); ++j) {
        Jx[o + i] += J(i, j) * x[d[j]];
        Jty[d[j]] += J(i, j) * y[o + i];
      }
  }
}

void Model::constraint_hessian_product(double t, const Vec& q, const Vec& w, const Mat& X,
                                       Mat& out) const {
  out.setZero(nq_, X.cols());
  LocalVec ql;
  LocalEqVec wl;
  LocalMat H;
  for (size_t c = 0; c < cons_.size(); ++c) {
    const auto d = cons_[c]->dofs();
    gather(q, d, ql);
    wl = w.segment(eq_offset_[c], cons_[c]->size());
    cons_[c]->hessian(t, ql, wl, H);
    for (size_t j = 0; j < d.size(); ++j)
      for (size_t i = 0; i < d.size(); ++i) {
        const double h = H(i, j);
        if (h != 0) out.row(d[i]) += h * X.row(d[j]);
      }
  }
}

namespace {
// Calls f(row, dofs, hv) for every constraint equation, hv = ∂²Φ_row/∂q² q̇ on the constraint's
// dofs: row `row` of ∂(Φ_q q̇)/∂q.
template <class F>
void for_each_velocity_jacobian_row(const std::vector<std::unique_ptr<ConstraintElement>>& cons,
                                    const std::vector<int>& eq_offset, double t, const Vec& q,
                                    const Vec& v, F&& f) {
  LocalVec ql, vl, hv;
  LocalEqVec w;
  LocalMat H;
  for (size_t c = 0; c < cons.size(); ++c) {
    const auto d = cons[c]->dofs();
    const int m = cons[c]->size();
    gather(q, d, ql);
    gather(v, d, vl);
    for (int i = 0; i < m; ++i) {
      w.setZero(m);
      w[i] = 1;
      cons[c]->hessian(t, ql, w, H);
      hv = H * vl;
      f(eq_offset[c] + i, d, hv);
    }
  }
}
}  // namespace

void Model::velocity_constraint_jacobian_product(double t, const Vec& q, const Vec& v, const Mat& X,
                                                 Mat& out) const {
  out.setZero(nc_, X.cols());
  for_each_velocity_jacobian_row(cons_, eq_offset_, t, q, v,
                                 [&](int row, std::span<const int> d, const LocalVec& hv) {
                                   for (size_t j = 0; j < d.size(); ++j)
                                     if (hv[j] != 0) out.row(row) += hv[j] * X.row(d[j]);
                                 });
}

void Model::velocity_constraint_jacobian_transpose_product(double t, const Vec& q, const Vec& v,
                                                           const Mat& Y, Mat& out) const {
  out.setZero(nq_, Y.cols());
  for_each_velocity_jacobian_row(cons_, eq_offset_, t, q, v,
                                 [&](int row, std::span<const int> d, const LocalVec& hv) {
                                   for (size_t j = 0; j < d.size(); ++j)
                                     if (hv[j] != 0) out.row(d[j]) += hv[j] * Y.row(row);
                                 });
}

void Model::constraint_time_terms(double t, const Vec& q, const Vec& v, const ModelParams& /*p*/,
                                  Vec& phi_t, Vec& gamma) const {
  phi_t.setZero(nc_);
  gamma.setZero(nc_);
  LocalEqVec pt, ptt, w;
  LocalVec ql, vl;
  LocalMat H;
  for (size_t c = 0; c < cons_.size(); ++c) {
    const auto d = cons_[c]->dofs();
    const int m = cons_[c]->size();
    gather(q, d, ql);
    gather(v, d, vl);
    cons_[c]->time_derivatives(t, pt, ptt);
    for (int i = 0; i < m; ++i) {
      w.setZero(m);
      w[i] = 1;
      cons_[c]->hessian(t, ql, w, H);
      phi_t[eq_offset_[c] + i] = pt[i];
      gamma[eq_offset_[c] + i] = vl.dot(H * vl) + ptt[i];
    }
  }
}

SpMat Model::constraint_hessian(double t, const Vec& q, const Vec& w) const {
  std::vector<Eigen::Triplet<double>> trip;
  LocalVec ql;
  LocalEqVec wl;
  LocalMat H;
  for (size_t c = 0; c < cons_.size(); ++c) {
    const auto d = cons_[c]->dofs();
    gather(q, d, ql);
    wl = w.segment(eq_offset_[c], cons_[c]->size());
    cons_[c]->hessian(t, ql, wl, H);
    for (size_t i = 0; i < d.size(); ++i)
      for (size_t j = 0; j < d.size(); ++j) trip.emplace_back(d[i], d[j], H(i, j));
  }
  SpMat m(nq_, nq_);
  m.setFromTriplets(trip.begin(), trip.end());
  return m;
}

SpMat Model::velocity_constraint_jacobian(double t, const Vec& q, const Vec& v) const {
  std::vector<Eigen::Triplet<double>> trip;
  for_each_velocity_jacobian_row(cons_, eq_offset_, t, q, v,
                                 [&](int row, std::span<const int> d, const LocalVec& hv) {
                                   for (size_t j = 0; j < d.size(); ++j)
                                     trip.emplace_back(row, d[j], hv[j]);
                                 });
  SpMat m(nc_, nq_);
  m.setFromTriplets(trip.begin(), trip.end());
  return m;
}

double Model::kinetic_energy(const State& s, const ModelParams& p) const {
  LocalState ls;
  ls.t = s.t;
  LocalVec r;
  LocalMat S;
  const Coefficients mass_only{1, 0, 0};
  double T = 0;
  for (const auto& f : forces_) {
    const auto d = f->dofs();
    const auto nd = static_cast<Eigen::Index>(d.size());
    gather(s.q, d, ls.q);
    gather(s.v, d, ls.v);
    ls.a.setZero(nd);
    r.setZero(nd);
    S.setZero(nd, nd);
    f->evaluate(ls, p, r, &mass_only, &S);
    T += 0.5 * ls.v.dot(S * ls.v);
  }
  return T;
}

double Model::strain_energy(const Vec& q, const ModelParams& p) const {
  double W = 0;
  for (const auto& b : flex_) {
    const double t = p.scalars[b->thickness_param], nu = p.scalars[b->nu_param],
                 E0 = p.scalars[b->E_param];
    double x[kMaxLocalDofs];
    for (int e = 0; e < b->mesh.num_elements(); ++e) {
      b->element_coordinates(e, q, x);
      W += b->elements[e]->strain_energy(x, p.fields[b->field][e] * E0, nu, t);
    }
  }
  for (const auto& b : solid_) {
    double x[kMaxLocalDofs];
    for (int e = 0; e < b->mesh.num_elements(); ++e) {
      b->element_coordinates(e, q, x);
      W += b->elements[static_cast<size_t>(e)]->strain_energy(x, b->element_E(e, p), b->nu(p));
    }
  }
  return W;
}

Model::Inversion Model::most_compressed_element(const Vec& q, const ModelParams& p) const {
  Inversion w;
  for (const auto& b : flex_) {
    const Vec& mu = p.fields[b->field];
    for (int e = 0; e < b->mesh.num_elements(); ++e) {
      if (!(mu[e] > kVoidMaterial)) continue;
      double x[kMaxLocalDofs];
      b->element_coordinates(e, q, x);
      if (const double d = b->elements[e]->min_det_F(x); !(d >= w.det_F)) {  // NaN counts too
        w.det_F = d;
        w.mu = mu[e];
        w.body = b.get();
        w.element = e;
      }
      if (const double d = b->elements[e]->min_corner_det_F(x); !(d >= w.corner_det_F)) {
        w.corner_det_F = d;
        w.corner_mu = mu[e];
        w.corner_body = b.get();
        w.corner_element = e;
      }
    }
  }
  return w;
}

namespace {
std::string element_text(const FlexibleBody* body, int element, const char* where, double d,
                         double mu) {
  char b[128];
  std::snprintf(b, sizeof b, " (det F = %.3g%s, μ_e = %.3g)", d, where, mu);
  return "flexible body '" + (body ? body->name : std::string("?")) + "', element " +
         std::to_string(element) + b;
}
}  // namespace

std::string Model::Inversion::describe() const {
  return element_text(body, element, "", det_F, mu);
}
std::string Model::Inversion::describe_fold() const {
  return element_text(corner_body, corner_element, " at a corner", corner_det_F, corner_mu);
}

}  // namespace lsmbs

namespace lsmbs {

void add_direction(ModelParams& params, const ParamDirection& d, double t) {
  for (const auto& f : d.fields) params.fields[f.field][f.element] += t * f.value;
  for (const auto& [j, v] : d.scalars) params.scalars[j] += t * v;
}

void Model::element_residual(int e, const State& s, const ModelParams& p, LocalVec& r) const {
  const auto d = forces_[e]->dofs();
  LocalState ls;
  ls.t = s.t;
  gather(s.q, d, ls.q);
  gather(s.v, d, ls.v);
  gather(s.a, d, ls.a);
  r.setZero(static_cast<Eigen::Index>(d.size()));
  forces_[e]->evaluate(ls, p, r, nullptr, nullptr);
}

void Model::mass_damping_product(const State& s, const ModelParams& p, const Mat& Qdd,
                                 const Mat& Vd, Mat& out) const {
  const int nc = static_cast<int>(Qdd.cols());
  out.setZero(nq_, nc);
  LocalState ls;
  ls.t = s.t;
  LocalMat M, C;
  for (const auto& f : forces_) {
    const auto d = f->dofs();
    const auto nd = static_cast<Eigen::Index>(d.size());
    gather(s.q, d, ls.q);
    gather(s.v, d, ls.v);
    gather(s.a, d, ls.a);
    f->mass_damping(ls, p, M, C);
    const bool has_c = !C.isZero(0.0);
    for (Eigen::Index j = 0; j < nd; ++j)  // skip structural zeros (quads: block-diagonal x/y mass)
      for (Eigen::Index i = 0; i < nd; ++i) {
        const double mij = M(i, j), cij = has_c ? C(i, j) : 0.0;
        if (mij == 0 && cij == 0) continue;
        for (int k = 0; k < nc; ++k) out(d[i], k) += mij * Qdd(d[j], k) + cij * Vd(d[j], k);
      }
  }
}

void Model::mass_damping_transpose_product(const State& s, const ModelParams& p, const Mat& Y,
                                           Mat& MtY, Mat& CtY) const {
  const auto nc = Y.cols();
  MtY.setZero(nq_, nc);
  CtY.setZero(nq_, nc);
  LocalState ls;
  ls.t = s.t;
  LocalMat M, C;
  for (const auto& f : forces_) {
    const auto d = f->dofs();
    const auto nd = static_cast<Eigen::Index>(d.size());
    gather(s.q, d, ls.q);
    gather(s.v, d, ls.v);
    gather(s.a, d, ls.a);
    f->mass_damping(ls, p, M, C);
    const bool has_c = !C.isZero(0.0);
    for (Eigen::Index j = 0; j < nd; ++j)
      for (Eigen::Index i = 0; i < nd; ++i) {
        const double mij = M(i, j), cij = has_c ? C(i, j) : 0.0;
        if (mij != 0) MtY.row(d[j]) += mij * Y.row(d[i]);
        if (cij != 0) CtY.row(d[j]) += cij * Y.row(d[i]);
      }
  }
}

void Model::element_mass_damping_product(int e, const State& s, const ModelParams& p,
                                         const Vec& qdd, const Vec& vd, LocalVec& out) const {
  const auto d = forces_[e]->dofs();
  const auto nd = static_cast<Eigen::Index>(d.size());
  LocalState ls;
  ls.t = s.t;
  gather(s.q, d, ls.q);
  gather(s.v, d, ls.v);
  gather(s.a, d, ls.a);
  LocalMat M, C;
  forces_[e]->mass_damping(ls, p, M, C);
  LocalVec a, v;
  gather(qdd, d, a);
  gather(vd, d, v);
  out = M.topLeftCorner(nd, nd) * a + C.topLeftCorner(nd, nd) * v;
}

void Model::mass_rate_product(const State& s, const ModelParams& p, const Vec& w, Vec& out) const {
  out.setZero(nq_);
  LocalState ls;
  ls.t = s.t;
  LocalVec r, v;
  LocalMat S1, S0;
  const Coefficients tangent{0, 0, 1};
  for (const auto& f : forces_) {
    if (!f->mass_depends_on_q()) continue;
    const auto d = f->dofs();
    const auto nd = static_cast<Eigen::Index>(d.size());
    gather(s.q, d, ls.q);
    ls.v.setZero(nd);  // at q̇ = 0 the velocity terms drop out of both tangents
    gather(w, d, ls.a);
    r.setZero(nd);
    S1.setZero(nd, nd);
    f->evaluate(ls, p, r, &tangent, &S1);
    ls.a.setZero(nd);
    S0.setZero(nd, nd);
    f->evaluate(ls, p, r, &tangent, &S0);
    gather(s.v, d, v);
    const LocalVec dm = (S1 - S0) * v;
    for (Eigen::Index i = 0; i < nd; ++i) out[d[i]] += dm[i];
  }
}

std::vector<int> Model::forces_touched_by(const ParamDirection& dir) const {
  std::vector<char> mark(forces_.size(), 0);
  for (const auto& f : dir.fields)
    if (const int e = force_of_field_entry(f.field, f.element); e >= 0) mark[e] = 1;
  for (const auto& [j, v] : dir.scalars)
    for (size_t e = 0; e < forces_.size(); ++e)
      if (forces_[e]->uses_parameter(j)) mark[e] = 1;
  std::vector<int> out;
  for (size_t e = 0; e < forces_.size(); ++e)
    if (mark[e]) out.push_back(static_cast<int>(e));
  return out;
}

void Model::for_each_param_partial(
    const State& s, const ModelParams& p, const ParamDirection& support,
    const std::function<void(bool field, size_t k, std::span<const int> dofs, const LocalVec& dr)>&
        fn) const {
  LocalState ls;
  ls.t = s.t;
  LocalVec dr;
  auto local = [&](const ForceElement& f) {
    const auto d = f.dofs();
    gather(s.q, d, ls.q);
    gather(s.v, d, ls.v);
    gather(s.a, d, ls.a);
    dr.setZero(static_cast<Eigen::Index>(d.size()));
    return d;
  };
  // material fields: the element that reads entry (field, element) adds its ∂r_e/∂μ_e
  for (size_t k = 0; k < support.fields.size(); ++k) {
    const auto& f = support.fields[k];
    const int e = force_of_field_entry(f.field, f.element);
    if (e < 0) continue;
    const auto d = local(*forces_[e]);
    forces_[e]->field_derivative(ls, p, dr);
    fn(true, k, d, dr);
  }
  // scalar parameters: each element that reads p_j adds its exact ∂r_e/∂p_j
  for (size_t k = 0; k < support.scalars.size(); ++k) {
    const int j = support.scalars[k].first;
    for (const auto& f : forces_) {
      if (!f->uses_parameter(j)) continue;
      const auto d = local(*f);
      f->param_derivative(ls, p, j, dr);
      fn(false, k, d, dr);
    }
  }
}

int Model::force_of_field_entry(int field, int entry) const {
  const auto at = [&](int first) {
    const int e = first + entry;
    const auto m = forces_[static_cast<size_t>(e)]->material_entry();
    return m.field == field && m.entry == entry ? e : -1;
  };
  for (const auto& b : flex_)
    if (b->field == field) return at(b->first_force);
  for (const auto& b : solid_)
    if (b->field == field) return at(b->first_force);
  return -1;
}

void Model::residual_param_derivative(const State& s, const ModelParams& p,
                                      const ParamDirection& dir, Vec& out) const {
  out.setZero(n());
  for_each_param_partial(s, p, dir,
                         [&](bool field, size_t k, std::span<const int> d, const LocalVec& dr) {
                           const double w = field ? dir.fields[k].value : dir.scalars[k].second;
                           for (size_t i = 0; i < d.size(); ++i)
                             out[d[i]] += w * dr[static_cast<Eigen::Index>(i)];
                         });
}

void Model::residual_param_contraction(const State& s, const ModelParams& p,
                                       const ParamDirection& support, const Mat& Y, Mat& fields,
                                       Mat& scalars) const {
  const auto ncols = Y.cols();
  fields.setZero(static_cast<Eigen::Index>(support.fields.size()), ncols);
  scalars.setZero(static_cast<Eigen::Index>(support.scalars.size()), ncols);
  for_each_param_partial(s, p, support,
                         [&](bool field, size_t k, std::span<const int> d, const LocalVec& dr) {
                           auto row = (field ? fields : scalars).row(static_cast<Eigen::Index>(k));
                           for (size_t i = 0; i < d.size(); ++i)
                             row += dr[static_cast<Eigen::Index>(i)] * Y.row(d[i]);
                         });
}

std::vector<double> Model::time_kinks(double t0, double t1) const {
  std::vector<double> t;
  for (const auto& c : cons_) c->time_kinks(t0, t1, t);
  std::sort(t.begin(), t.end());
  t.erase(std::unique(t.begin(), t.end()), t.end());
  return t;
}

}  // namespace lsmbs
