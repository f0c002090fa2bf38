// Study::prepare — the start checks of a study, whatever built it (a case file, the Python
// builder, or code): what the loader refuses once the model is built, and what a study changed
// afterwards (options or parameters set from Python) must meet again before it runs. They read
// the model, the options and the study's ModelStart (what the building of the model knew: the
// placed state, the given velocities, which entity made each force element), never a document:
// an error names the subject ("joints", "simulation.k", "responses.2.window") or the entity (a
// body, joint or force by name), and io/ maps that to the case file's JSON path (locate).
#include <Eigen/OrderingMethods>
#include <Eigen/SparseQR>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "lsmbs/core/error.hpp"
#include "lsmbs/integrators/initial_state.hpp"
#include "lsmbs/mbs/linear_solver_setup.hpp"
#include "lsmbs/mbs/spatial.hpp"
#include "lsmbs/sensitivity/study.hpp"

namespace lsmbs {

namespace {

// Redundant or conflicting constraints, seen before any run: the rows of Φ_q at the initial
// positions must be independent (rank-revealing sparse QR of Φ_qᵀ). The dependent rows are
// named by their joints — e.g. a duplicated bearing, or two prismatic joints that both lock a
// body's rotation — instead of a singular iteration matrix later blaming another joint.
void check_constraint_rank(const Study& cs) {
  const Model& m = *cs.model;
  if (m.nc() == 0 || !cs.check_constraints) return;
  SpMat Jt = m.constraint_jacobian(0.0, m.initial_positions(), m.params()).transpose();
  Jt.makeCompressed();
  Eigen::SparseQR<SpMat, Eigen::COLAMDOrdering<int>> qr;
  qr.compute(Jt);
  if (qr.info() != Eigen::Success || qr.rank() >= m.nc()) return;
  std::string dependent;
  const auto& perm = qr.colsPermutation().indices();
  const int shown = std::min<int>(m.nc() - static_cast<int>(qr.rank()), 6);
  for (int k = static_cast<int>(qr.rank()); k < static_cast<int>(qr.rank()) + shown; ++k)
    dependent += (dependent.empty() ? "" : "; ") + m.describe_unknown(m.nq() + perm[k]);
  throw SetupError(
      "joints",
      std::to_string(m.nc() - qr.rank()) + " of the " + std::to_string(m.nc()) +
          " constraint equations are redundant or conflicting at t = 0 (the rows of the constraint "
          "Jacobian are dependent): " +
          dependent +
          (m.spatial_bodies().empty()
               ? " — remove the duplicated joint, or unlock a rotation (\"lock_rotation\": false) "
                 "locked twice"
               : " — remove the duplicated joint, or replace a joint whose equations others "
                 "already "
                 "impose by one that leaves that freedom (a spherical for a universal, a "
                 "cylindrical for a revolute; docs/case-format.md, \"Spatial cases\")"));
}

// Values beyond double precision, seen before any run: every force element's residual and
// iteration-matrix block at the initial state with the case's h (the first Newton matrix of
// Algorithm 1, S = β′M + γ′C_t + K_t), the assembled matrix with the automatic scaling k = ζ, and
// the constraints Φ, Φ_t and γ at t = 0 must be finite. A mass of 1e308 kg, for instance,
// overflows in β′M; without this check the KLU factorization of the start system fails and blames
// an unrelated joint. The message names the entity that made the element and its parameters.
void check_finite_start(const Study& cs) {
  const Model& m = *cs.model;
  const ModelParams& p = m.params();
  const AlphaCoefficients c = AlphaCoefficients::make(cs.simulation.rho_inf, cs.simulation.h);
  const Coefficients co{c.beta_p, c.gamma_p, 1.0};
  char when[160];
  std::snprintf(when, sizeof when, "at t = 0 with h = %g s (β′ = %.3g s⁻²)", cs.simulation.h,
                c.beta_p);
  auto owner_of = [&](size_t force) {  // the body or force that added it (empty: unknown)
    return force < cs.start.force_owners.size() ? cs.start.force_owners[force] : std::string();
  };
  auto parameters_of = [&](const std::string& name) {  // "(mass = 1e+308, inertia = 0.1)"
    std::string out;
    char buf[64];
    const auto ps = cs.start.entity_parameters.find(name);
    if (ps == cs.start.entity_parameters.end()) return std::string();
    for (int i : ps->second) {
      std::snprintf(buf, sizeof buf, "%s = %g",
                    m.parameter_names()[i].substr(name.size() + 1).c_str(), p.scalars[i]);
      out += (out.empty() ? "" : ", ") + std::string(buf);
    }
    return out.empty() ? std::string() : " (" + out + ")";
  };
  const Vec& q = cs.initial.q;
  const Vec& v = cs.initial.v;
  const auto& forces = m.forces();
  double s_max = 0;  // the largest iteration-matrix entry of one element, and which element
  size_t f_max = 0;
  for (size_t f = 0; f < forces.size(); ++f) {
    const auto d = forces[f]->dofs();
    const auto nd = static_cast<Eigen::Index>(d.size());
    LocalState ls;
    ls.q.resize(nd), ls.v.resize(nd), ls.a.setZero(nd);
    for (Eigen::Index i = 0; i < nd; ++i) ls.q[i] = q[d[i]], ls.v[i] = v[d[i]];
    LocalVec r = LocalVec::Zero(nd);
    LocalMat S = LocalMat::Zero(nd, nd);
    forces[f]->evaluate(ls, p, r, &co, &S);
    if (r.allFinite() && S.allFinite()) {
      if (nd && S.cwiseAbs().maxCoeff() > s_max) s_max = S.cwiseAbs().maxCoeff(), f_max = f;
      continue;
    }
    const std::string e = owner_of(f);
    throw SetupError("",
                     forces[f]->describe() + ": its forces or iteration matrix are not finite " +
                         when + ": a value is beyond double precision; check its parameters" +
                         parameters_of(e) + ", its initial velocity and the gravity",
                     e);
  }
  // The factorization of [S kΦ_qᵀ; kΦ_q 0] forms products of entries (k²/S in the pivots of the
  // constraint rows, with k the mean diagonal of S): entries beyond ~1e100 overflow there even
  // though each one is finite (a spring of 1e308 N/m failed as "consistent initial accelerations
  // are not finite"). Physical models are far below: a steel plate's stiffness entries are of the
  // order E·t ≈ 2e9 N/m, β′M at h = 1 µs about 1e12 times its masses.
  constexpr double kMaxEntry = 1e100;
  if (s_max > kMaxEntry) {
    const std::string e = owner_of(f_max);
    char buf[96];
    std::snprintf(buf, sizeof buf, "its iteration-matrix entries reach %.3g ", s_max);
    throw SetupError("",
                     forces[f_max]->describe() + ": " + buf + when +
                         ": beyond 1e100 the sparse factorization overflows; check its parameters" +
                         parameters_of(e),
                     e);
  }
  Vec phi, phi_t, gamma;
  m.constraints(0.0, q, p, phi);
  m.constraint_time_terms(0.0, q, v, p, phi_t, gamma);
  for (Eigen::Index i = 0; i < phi.size(); ++i)
    if (!std::isfinite(phi[i]) || !std::isfinite(phi_t[i]) || !std::isfinite(gamma[i])) {
      std::string joint;
      for (size_t k = 0; k < m.constraints().size(); ++k)
        if (i >= m.constraint_offset(static_cast<int>(k)) &&
            i < m.constraint_offset(static_cast<int>(k)) + m.constraints()[k]->size())
          joint = m.constraints()[k]->name();
      throw SetupError(
          "joints",
          m.describe_unknown(m.nq() + static_cast<int>(i)) +
              ": the constraint, its velocity or its acceleration term is not finite at t = 0 "
              "(a position, velocity or driver law value beyond double precision)",
          joint);
    }
  const double k = GeneralizedAlpha::automatic_scaling(m, p, cs.initial, c);
  // A scaling or penalty far from the automatic one makes the constraint rows dominate (or vanish
  // in) the iteration matrix: the results then carry round-off of that ratio (ζ = 1e300 gave a
  // side force of 1e277 N, exit 0). The results do not depend on them within 1e-3 ... 1e3
  // (test_pendulum); more than 1e8 away is refused.
  for (const auto& [key, value] :
       {std::pair<const char*, double>{"k", cs.simulation.k}, {"zeta", cs.simulation.zeta}})
    if (value > 0 && std::isfinite(k) && k > 0 && (value > 1e8 * k || value < 1e-8 * k)) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "%g is more than 1e8 times away from the automatic scaling %.3g of this model "
                    "(give 0 for the automatic value)",
                    value, k);
      throw SetupError(std::string("simulation.") + key, buf);
    }
  std::vector<double> vals;
  m.iteration_matrix(cs.initial, p, co, cs.simulation.k > 0 ? cs.simulation.k : k,
                     cs.simulation.zeta > 0 ? cs.simulation.zeta : k, vals);
  const auto& pat = m.pattern();
  for (int col = 0; col < pat.n; ++col)
    for (int at = pat.col_ptr[col]; at < pat.col_ptr[col + 1]; ++at)
      if (!std::isfinite(vals[at]) || !std::isfinite(k))
        throw SetupError("simulation",
                         "the iteration matrix is not finite " + std::string(when) +
                             " in the equations of " + m.describe_unknown(col) +
                             " (the sum of its masses or stiffnesses overflows; automatic "
                             "scaling k = " +
                             std::to_string(k) + "): a value is beyond double precision");
}

// Initial velocities the case gives are kept; the others follow from the constraints
// (integrators/initial_state.hpp). Given velocities that contradict the constraints are an input
// error naming the first body concerned. Positions and velocities are projected here, so that
// every run starts from the same consistent state.
void hold_given_velocities(Study& cs) {
  const auto& given = cs.start.given_velocities;
  std::vector<char> held = cs.start.held_velocities;  // resized to the unknowns below
  const Model& m = *cs.model;
  if (given.empty() || m.nc() == 0 || !cs.simulation.project_initial) return;
  held.resize(m.nq(), 0);
  SparseLU lu;
  analyze_model_matrix(lu, m, cs.simulation.linear_solver, cs.simulation.ordering);
  ProjectionReport rep;
  State s = cs.initial;
  const Status st =
      project_initial_state(m, m.params(), s, lu, 1e-13 * m.length_scale(), &rep, &held);
  if (st.ok()) cs.initial = s;
  if (st.ok() || rep.conflicting_rows.empty()) return;  // other failures: reported by the run
  const GivenVelocity* first = nullptr;  // the first body whose given velocities conflict
  for (const auto& g : given)
    for (int j : rep.conflicting_held)
      if (j >= g.first && j < g.end && !first) first = &g;
  throw SetupError("bodies",
                   st.message +
                       " — give only the velocities that determine the motion (the others are "
                       "computed), or velocities that satisfy the joints and drivers at t = 0",
                   first ? first->body : "", first ? first->field : "");
}

// The initial projection (simulation.project_initial) corrects bodies placed approximately. A
// body it moves by more than 10 % of the model's length scale or 0.1 rad is a case whose
// placement contradicts its joints or drivers at t = 0 (a crank drawn at 90° whose driver's law
// starts from 0 was rotated silently, and a flexible coupler attached to it torn): refused,
// naming the body and the move. Failed projections are left to the run, which reports them.
void check_initial_placement(const Study& cs, const State& placed) {
  const Model& m = *cs.model;
  if (m.nc() == 0 || !cs.simulation.project_initial) return;
  SparseLU lu;
  analyze_model_matrix(lu, m, cs.simulation.linear_solver, cs.simulation.ordering);
  State s = placed;
  if (!project_initial_state(m, m.params(), s, lu, 1e-13 * m.length_scale()).ok()) return;
  const double L = m.length_scale(), kMove = 0.1;
  double worst = 0;  // the largest move, relative to its allowance
  std::string body, what;
  auto consider = [&](const std::string& name, double move, double allowance,
                      const std::string& text) {
    if (move / allowance > worst) worst = move / allowance, body = name, what = text;
  };
  char b[160];
  for (const auto& r : m.rigid_bodies()) {
    const int i = r.dof0;
    const double dx = s.q[i] - placed.q[i], dy = s.q[i + 1] - placed.q[i + 1],
                 dth = s.q[i + 2] - placed.q[i + 2];
    std::snprintf(b, sizeof b, "moves it by %.4g m (from (%.6g, %.6g) to (%.6g, %.6g))",
                  std::hypot(dx, dy), placed.q[i], placed.q[i + 1], s.q[i], s.q[i + 1]);
    consider(r.name, std::hypot(dx, dy), kMove * L, b);
    std::snprintf(b, sizeof b, "rotates it by %.4g rad = %.3g° (angle %.6g → %.6g rad)", dth,
                  dth * 180 / std::numbers::pi, placed.q[i + 2], s.q[i + 2]);
    consider(r.name, std::abs(dth), kMove, b);
  }
  for (const auto& r : m.spatial_bodies()) {
    // the centre of mass's move, and the angle of the rotation between the principal frames
    // (from the frames as placed and as projected, each orthonormal to the projection's tolerance)
    const SpatialPose a = SpatialPose::read(r.dof0, placed.q), z = SpatialPose::read(r.dof0, s.q);
    const double d = (z.r - a.r).norm();
    std::snprintf(b, sizeof b, "moves it by %.4g m (from (%.6g, %.6g, %.6g) to (%.6g, %.6g, %.6g))",
                  d, a.r.x(), a.r.y(), a.r.z(), z.r.x(), z.r.y(), z.r.z());
    consider(r.name, d, kMove * L, b);
    const double angle =
        std::acos(std::clamp(((a.R.transpose() * z.R).trace() - 1) / 2, -1.0, 1.0));
    std::snprintf(b, sizeof b, "rotates it by %.4g rad = %.3g°", angle,
                  angle * 180 / std::numbers::pi);
    consider(r.name, angle, kMove, b);
  }
  for (const auto& f : m.flexible_bodies())
    for (int n = 0; n < f->mesh.num_nodes(); ++n) {
      const int i = f->dof0 + 2 * n;
      const double d = std::hypot(s.q[i] - placed.q[i], s.q[i + 1] - placed.q[i + 1]);
      std::snprintf(b, sizeof b, "moves its node %d by %.4g m", n, d);
      consider(f->name, d, kMove * L, b);
    }
  // The projection is the smallest correction of all coordinates together: for a flexible body
  // it moves some nodes and not others, and leaves the body strained at t = 0. A hub drawn
  // 0.001 rad off its driver's start put 5e-5 of strain into the arm welded to it, whose tool then
  // vibrated with 4.6 times the deflection of the arm drawn in place (complete, and wrong). The
  // strain the projection adds (Green–Lagrange, element centres) must stay below kStrain.
  constexpr double kStrain = 1e-7;
  double strain = 0;
  std::string strained, strain_what;
  for (const auto& f : m.flexible_bodies())
    for (int e = 0; e < f->mesh.num_elements(); ++e) {
      double x0[kMaxLocalDofs], x1[kMaxLocalDofs];
      f->element_coordinates(e, placed.q, x0);
      f->element_coordinates(e, s.q, x1);
      Eigen::Vector3d E0, E1;
      Mat2 F0, F1;
      f->elements[static_cast<size_t>(e)]->centre_strain(x0, E0, F0);
      f->elements[static_cast<size_t>(e)]->centre_strain(x1, E1, F1);
      if (const double d = (E1 - E0).lpNorm<Eigen::Infinity>(); d > strain) {
        strain = d;
        std::snprintf(b, sizeof b, "strains its element %d by %.3g (Green–Lagrange, at the centre)",
                      e, d);
        strained = f->name, strain_what = b;
      }
    }
  if (worst <= 1 && strain > kStrain) {  // name the body the projection moved most, and the strain
    if (body.empty() || body == strained)
      body = strained, what = strain_what;
    else
      what += ", which strains flexible body '" + strained + "': " + strain_what.substr(8);
    worst = 2;
  }
  if (worst <= 1) return;
  throw SetupError(
      "bodies",
      "body '" + body +
          "' does not satisfy the joints and drivers at t = 0: projecting "
          "the initial state onto them " +
          what +
          ". Place it where they put it at t = 0 "
          "(check a driver's law value at t = 0 against the body's angle or position); the "
          "projection corrects placements only within 10 % of the model's length scale "
          "(L = " +
          std::to_string(L) +
          " m) and 0.1 rad, and a flexible body's only while it strains the body by less "
          "than 1e-7",
      body);
}

// Every response window must contain a time step of the run [0, t_end].
void check_response_windows(const Study& cs) {
  for (size_t i = 0; i < cs.responses.size(); ++i) {
    const auto& r = cs.responses[i];
    const double h = cs.simulation.h, a = std::max(r.t0, 0.0),
                 b = std::min(r.t1, cs.simulation.t_end);
    const double k_first = std::ceil(a / h - 1e-9), k_last = std::floor(b / h + 1e-9);
    if (b < a || k_last < k_first)
      throw SetupError(
          "responses." + std::to_string(i) + (r.t0 > -1e299 || r.t1 < 1e299 ? ".window" : ""),
          "the window (" + r.window_text + ") contains no time step of the run [0, " +
              std::to_string(cs.simulation.t_end) + "] s with h = " + std::to_string(h));
  }
}

// Every measure must be finite at the initial state (a point 1e300 m away made a distance, and
// every response of it, Inf or NaN in a run reported complete).
void check_finite_measures(const Study& cs) {
  std::vector<double> vals;
  for (size_t i = 0; i < cs.measures.size(); ++i) {
    vals.assign(cs.measures[i]->components().size(), 0.0);
    cs.measures[i]->evaluate(*cs.model, cs.initial, cs.model->params(), vals.data());
    for (double v : vals)
      if (!std::isfinite(v))
        throw SetupError("measures." + std::to_string(i),
                         "measure '" + cs.measures[i]->name() +
                             "' is not finite at t = 0 (a point or value beyond double precision)");
  }
}

}  // namespace

void Study::prepare(const Vec* design) {
  // a case file's loader refuses invalid options as it reads them; a study changed later (or
  // built in code) meets them here
  if (auto msg = simulation.validate(); !msg.empty()) {
    const auto colon = msg.find(": ");
    throw SetupError("simulation." + msg.substr(0, colon), msg.substr(colon + 2));
  }
  check_constraint_rank(*this);
  check_response_windows(*this);
  if (this->design)
    this->design->apply(design ? *design : this->design->initial(), model->params());
  // every check and every run starts from the study's placement (a study without one keeps the
  // initial state it was given)
  if (start.placed.q.size() == model->nq()) initial = start.placed;
  check_finite_start(*this);
  hold_given_velocities(*this);
  check_initial_placement(*this, start.placed.q.size() == model->nq() ? start.placed : initial);
  check_finite_measures(*this);
}

}  // namespace lsmbs
