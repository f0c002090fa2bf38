#pragma once
// Central-difference checks of one force or constraint element's local derivatives: the
// constraint Jacobian Φ_q, the Hessian contraction Σ_i w_i ∂²Φ_i/∂q² and the rheonomic Φ_t, Φ_tt;
// a force element's tangent S = c_a M + c_v C + c_q K and its parameter derivatives ∂r/∂p_j.
#include <algorithm>
#include <random>

#include "lsmbs/mbs/elements.hpp"

namespace lsmbs::checks {

inline LocalVec random_local(int n, std::mt19937& rng, double scale = 1) {
  std::uniform_real_distribution<double> U(-scale, scale);
  LocalVec q(n);
  for (int i = 0; i < n; ++i) q[i] = U(rng);
  return q;
}

struct ConstraintErrors {
  double jacobian = 0, hessian = 0, time = 0;
};

/// Largest absolute differences of Φ_q, Σ w_i ∂²Φ_i/∂q² and (Φ_t, Φ_tt) against central
/// differences with step d at (t, q).
inline ConstraintErrors check_constraint(const ConstraintElement& c, double t, const LocalVec& q,
                                         const LocalEqVec& w, double d = 1e-6) {
  const ModelParams p;
  const auto n = q.size();
  LocalEqVec phi, phi_p, phi_m;
  LocalJac J, Jp, Jm;
  c.evaluate(t, q, p, phi, &J);
  LocalMat H;
  c.hessian(t, q, w, H);
  ConstraintErrors e;
  for (Eigen::Index j = 0; j < n; ++j) {
    LocalVec qp = q, qm = q;
    qp[j] += d, qm[j] -= d;
    c.evaluate(t, qp, p, phi_p, &Jp);
    c.evaluate(t, qm, p, phi_m, &Jm);
    e.jacobian = std::max(e.jacobian, ((phi_p - phi_m) / (2 * d) - J.col(j)).cwiseAbs().maxCoeff());
    // column j of Σ_i w_i ∂²Φ_i/∂q² = ∂(Φ_qᵀ w)/∂q_j
    const LocalVec col = (Jp.transpose() * w - Jm.transpose() * w) / (2 * d);
    e.hessian = std::max(e.hessian, (col - H.col(j)).cwiseAbs().maxCoeff());
  }
  LocalEqVec phi_t, phi_tt, ft_p, ftt_p, ft_m, ftt_m;
  c.time_derivatives(t, phi_t, phi_tt);
  c.evaluate(t + d, q, p, phi_p, nullptr);
  c.evaluate(t - d, q, p, phi_m, nullptr);
  c.time_derivatives(t + d, ft_p, ftt_p);
  c.time_derivatives(t - d, ft_m, ftt_m);
  e.time = std::max(((phi_p - phi_m) / (2 * d) - phi_t).cwiseAbs().maxCoeff(),
                    ((ft_p - ft_m) / (2 * d) - phi_tt).cwiseAbs().maxCoeff());
  return e;
}

struct ForceErrors {
  double stiffness = 0, damping = 0, mass = 0, parameters = 0;
};

/// Largest absolute differences of K = ∂r/∂q, C = ∂r/∂q̇, M = ∂r/∂q̈ (from S with one coefficient
/// set at a time) and of ∂r/∂p_j (every parameter the element uses) against central differences.
inline ForceErrors check_force(const ForceElement& f, const LocalState& s, const ModelParams& p,
                               double d = 1e-6) {
  const auto n = s.q.size();
  const auto residual = [&](const LocalState& x, const ModelParams& px) {
    LocalVec r = LocalVec::Zero(n);
    f.evaluate(x, px, r, nullptr, nullptr);
    return r;
  };
  const auto tangent = [&](Coefficients co) {
    LocalVec r = LocalVec::Zero(n);
    LocalMat S = LocalMat::Zero(n, n);
    f.evaluate(s, p, r, &co, &S);
    return S;
  };
  const LocalMat K = tangent({0, 0, 1}), C = tangent({0, 1, 0}), M = tangent({1, 0, 0});
  ForceErrors e;
  for (Eigen::Index j = 0; j < n; ++j) {
    for (int which = 0; which < 3; ++which) {
      LocalState sp = s, sm = s;
      LocalVec& xp = which == 0 ? sp.q : which == 1 ? sp.v : sp.a;
      LocalVec& xm = which == 0 ? sm.q : which == 1 ? sm.v : sm.a;
      xp[j] += d, xm[j] -= d;
      const LocalVec col = (residual(sp, p) - residual(sm, p)) / (2 * d);
      const LocalMat& T = which == 0 ? K : which == 1 ? C : M;
      double& err = which == 0 ? e.stiffness : which == 1 ? e.damping : e.mass;
      err = std::max(err, (col - T.col(j)).cwiseAbs().maxCoeff());
    }
  }
  for (size_t j = 0; j < p.scalars.size(); ++j) {
    if (!f.uses_parameter(static_cast<int>(j))) continue;
    ModelParams pp = p, pm = p;
    const double h = d * std::max(1.0, std::abs(p.scalars[j]));
    pp.scalars[j] += h, pm.scalars[j] -= h;
    LocalVec dr = LocalVec::Zero(n);
    f.param_derivative(s, p, static_cast<int>(j), dr);
    const LocalVec fd = (residual(s, pp) - residual(s, pm)) / (2 * h);
    e.parameters = std::max(e.parameters, (fd - dr).cwiseAbs().maxCoeff());
  }
  return e;
}

}  // namespace lsmbs::checks
