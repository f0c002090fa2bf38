#include "lsmbs/integrators/ggl_system.hpp"

#include <vector>

namespace lsmbs {

State GglSystem::state(double t, const double* y, const double* yp) const {
  State s;
  s.t = t;
  s.q = Eigen::Map<const Vec>(y, nq_);
  s.v = Eigen::Map<const Vec>(y + nq_, nq_);
  s.lambda = Eigen::Map<const Vec>(y + 2 * nq_, nc_);
  s.a = Eigen::Map<const Vec>(yp + nq_, nq_);
  return s;
}

bool GglSystem::residual(const ModelParams& p, double t, const double* y, const double* yp,
                         double* F) {
  const int nq = nq_, nc = nc_;
  const State s = state(t, y, yp);
  m_.residual(s, p, 1.0, 0.0, R_);
  if (!R_.allFinite()) return false;
  const SpMat J = m_.constraint_jacobian(t, s.q, p);
  m_.constraint_time_terms(t, s.q, s.v, p, phi_t_, gamma_);
  const Eigen::Map<const Vec> qd(yp, nq), mu(y + 2 * nq + nc, nc);
  Eigen::Map<Vec>(F, nq) = sc_.s1 * (qd - s.v + J.transpose() * mu);
  Eigen::Map<Vec>(F + nq, nq) = R_.head(nq);
  Eigen::Map<Vec>(F + 2 * nq, nc) = sc_.s3 * R_.tail(nc);
  Eigen::Map<Vec>(F + 2 * nq + nc, nc) = sc_.s4 * (J * s.v + phi_t_);
  return true;
}

SpMat GglSystem::jacobian(const ModelParams& p, double t, double cj, const double* y,
                          const double* yp) {
  const int nq = nq_, nc = nc_, N = n_;
  const double s1 = sc_.s1, s3 = sc_.s3, s4 = sc_.s4;
  const State s = state(t, y, yp);
  m_.iteration_matrix(s, p, Coefficients{0, 0, 1}, 1.0, 0.0, vals_);
  const SpMat A = m_.assembler().to_sparse(vals_);  // [K + H(λ)  Φ_qᵀ ; Φ_q  0]
  m_.iteration_matrix(s, p, Coefficients{cj, 1, 0}, 1.0, 0.0, vals_);
  const SpMat B = m_.assembler().to_sparse(vals_);  // q-block: cj M + C
  const Vec mu = Eigen::Map<const Vec>(y + 2 * nq + nc, nc);
  const SpMat Hmu = m_.constraint_hessian(t, s.q, mu);
  const SpMat Vj = m_.velocity_constraint_jacobian(t, s.q, s.v);
  std::vector<Eigen::Triplet<double>> tr;
  tr.reserve(A.nonZeros() * 3 + Hmu.nonZeros() + Vj.nonZeros() + 2 * nq);
  const int oq = 0, ov = nq, ol = 2 * nq, om = 2 * nq + nc;  // column offsets
  const int r1 = 0, r2 = nq, r3 = 2 * nq, r4 = 2 * nq + nc;  // row offsets
  for (int i = 0; i < nq; ++i) {
    tr.emplace_back(r1 + i, oq + i, s1 * cj);
    tr.emplace_back(r1 + i, ov + i, -s1);
  }
  for (int k = 0; k < Hmu.outerSize(); ++k)
    for (SpMat::InnerIterator it(Hmu, k); it; ++it)
      tr.emplace_back(r1 + it.row(), oq + it.col(), s1 * it.value());
  for (int k = 0; k < A.outerSize(); ++k)
    for (SpMat::InnerIterator it(A, k); it; ++it) {
      const int i = static_cast<int>(it.row()), j = static_cast<int>(it.col());
      if (i < nq && j < nq) {
        tr.emplace_back(r2 + i, oq + j, it.value());
      } else if (i < nq) {
        tr.emplace_back(r2 + i, ol + (j - nq), it.value());  // Φ_qᵀ → λ
      } else if (j < nq) {
        tr.emplace_back(r3 + (i - nq), oq + j, s3 * it.value());  // Φ_q → F3
        tr.emplace_back(r4 + (i - nq), ov + j, s4 * it.value());  // Φ_q → F4 (v)
        tr.emplace_back(r1 + j, om + (i - nq), s1 * it.value());  // Φ_qᵀ → F1 (μ)
      }
    }
  for (int k = 0; k < B.outerSize(); ++k)
    for (SpMat::InnerIterator it(B, k); it; ++it)
      if (it.row() < nq && it.col() < nq) tr.emplace_back(r2 + it.row(), ov + it.col(), it.value());
  for (int k = 0; k < Vj.outerSize(); ++k)
    for (SpMat::InnerIterator it(Vj, k); it; ++it)
      tr.emplace_back(r4 + it.row(), oq + it.col(), s4 * it.value());
  SpMat Jm(N, N);
  Jm.setFromTriplets(tr.begin(), tr.end());
  Jm.makeCompressed();
  return Jm;
}

void GglSystem::sensitivity_residual(const ModelParams& p, double t, const double* y,
                                     const double* yp, std::span<const ParamDirection> dirs,
                                     std::span<const double* const> yS,
                                     std::span<const double* const> ypS,
                                     std::span<double* const> rS) {
  const int nq = nq_, N = n_;
  const State s = state(t, y, yp);
  // M = S(1, 0, 0) − S(0, 0, 0) (the iteration matrix is linear in its coefficients)
  m_.iteration_matrix(s, p, Coefficients{0, 0, 0}, 1.0, 0.0, vals_);
  const std::vector<double> v0 = vals_;
  m_.iteration_matrix(s, p, Coefficients{1, 0, 0}, 1.0, 0.0, vals_);
  std::vector<double> vm = vals_;
  for (size_t k = 0; k < vals_.size(); ++k) vm[k] -= v0[k];
  const SpMat M = m_.assembler().to_sparse(vm).topLeftCorner(nq, nq);
  const SpMat Jy = jacobian(p, t, 0.0, y, yp);  // F_y (c_j = 0)
  for (size_t i = 0; i < rS.size(); ++i) {
    const Eigen::Map<const Vec> ys(yS[i], N), yps(ypS[i], N);
    Eigen::Map<Vec> out(rS[i], N);
    out = Jy * ys;
    // F_ẏ ẏS = [s₁ q̇S; M v̇S; 0; 0]
    out.head(nq) += sc_.s1 * yps.head(nq);
    out.segment(nq, nq) += M * yps.segment(nq, nq);
    m_.residual_param_derivative(s, p, dirs[i], dr_);
    out.segment(nq, nq) += dr_.head(nq);
  }
}

void GglSystem::pattern_transpose_product(const std::vector<double>& v, const Vec& x,
                                          Vec& out) const {
  const CscPattern& P = m_.pattern();
  out.resize(P.n);
  for (int j = 0; j < P.n; ++j) {
    double acc = 0;
    for (int k = P.col_ptr[j]; k < P.col_ptr[j + 1]; ++k) acc += v[k] * x[P.row_ind[k]];
    out[j] = acc;
  }
}

bool GglSystem::adjoint_residual(const ModelParams& p, double t, const double* y, const double* yp,
                                 const double* xi_, const double* xid_, const Vec& gq,
                                 const Vec& gv, double* rB) {
  const int nq = nq_, nc = nc_, N = n_;
  const double s1 = sc_.s1, s3 = sc_.s3, s4 = sc_.s4;
  const State s = state(t, y, yp);
  const Eigen::Map<const Vec> xi(xi_, N), xid(xid_, N);
  const auto xq = xi.head(nq), xv = xi.segment(nq, nq), xl = xi.segment(2 * nq, nc),
             xm = xi.tail(nc);
  // F_yᵀ ξ from transposed products with the model's blocks on its pattern:
  //   [K_t Φ_qᵀ; Φ_q 0]ᵀ [ξ_v; s₃ξ_λ] = [K_tᵀξ_v + s₃Φ_qᵀξ_λ; Φ_q ξ_v]
  //   [C_t Φ_qᵀ; Φ_q 0]ᵀ [ξ_v; s₄ξ_μ] = [C_tᵀξ_v + s₄Φ_qᵀξ_μ; Φ_q ξ_v],  and Φ_q ξ_q
  m_.iteration_matrix(s, p, Coefficients{0, 0, 1}, 1.0, 0.0, vals_);
  adj_x_.resize(nq + nc);
  adj_x_ << xv, s3 * xl;
  pattern_transpose_product(vals_, adj_x_, adj_yk_);
  m_.iteration_matrix(s, p, Coefficients{0, 1, 0}, 1.0, 0.0, vals_);
  adj_x_ << xv, s4 * xm;
  pattern_transpose_product(vals_, adj_x_, adj_yc_);
  adj_x_ << xq, Vec::Zero(nc);
  pattern_transpose_product(vals_, adj_x_, adj_yq_);
  const SpMat Hmu = m_.constraint_hessian(t, s.q, Eigen::Map<const Vec>(y + 2 * nq + nc, nc));
  const SpMat Vj = m_.velocity_constraint_jacobian(t, s.q, s.v);
  Eigen::Map<Vec> r(rB, N);
  r.head(nq) =
      s1 * xid.head(nq) - (s1 * (Hmu * xq) + adj_yk_.head(nq) + s4 * (Vj.transpose() * xm)) + gq;
  adj_a_ = xid.segment(nq, nq);
  adj_zero_.setZero(nq, 1);
  m_.mass_damping_product(s, p, adj_a_, adj_zero_, adj_ma_);  // M ξ̇_v (C·0)
  m_.mass_rate_product(s, p, xv, adj_mw_);                    // Ṁ ξ_v
  r.segment(nq, nq) = adj_ma_.col(0) + adj_mw_ - (-s1 * xq + adj_yc_.head(nq)) + gv;
  r.segment(2 * nq, nc) = -adj_yk_.tail(nc);
  r.tail(nc) = -s1 * adj_yq_.tail(nc);
  return r.allFinite();
}

}  // namespace lsmbs
