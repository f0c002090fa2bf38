#include "lsmbs/integrators/ggl_system.hpp"

#include <vector>

namespace lsmbs {

State GglSystem::state(double t, const double* y, const double* yp) const {
  State s;
  state_into(t, y, yp, s);
  return s;
}

void GglSystem::state_into(double t, const double* y, const double* yp, State& s) const {
  s.t = t;
  s.q = Eigen::Map<const Vec>(y, nq_);  // no allocation once s has its sizes
  s.v = Eigen::Map<const Vec>(y + nq_, nq_);
  s.lambda = Eigen::Map<const Vec>(y + 2 * nq_, nc_);
  s.a = Eigen::Map<const Vec>(yp + nq_, nq_);
}

bool GglSystem::residual(const ModelParams& p, double t, const double* y, const double* yp,
                         double* F) {
  const int nq = nq_, nc = nc_;
  state_into(t, y, yp, st_);
  const State& s = st_;
  m_.residual(s, p, 1.0, 0.0, R_);
  if (!R_.allFinite()) return false;
  mu_ = Eigen::Map<const Vec>(y + 2 * nq + nc, nc);
  m_.constraint_jacobian_products(t, s.q, p, s.v, mu_, jv_, jtmu_);  // Φ_q v, Φ_qᵀ μ
  m_.constraint_time_terms(t, s.q, s.v, p, phi_t_, gamma_);
  const Eigen::Map<const Vec> qd(yp, nq);
  Eigen::Map<Vec>(F, nq) = sc_.s1 * (qd - s.v + jtmu_);
  Eigen::Map<Vec>(F + nq, nq) = R_.head(nq);
  Eigen::Map<Vec>(F + 2 * nq, nc) = sc_.s3 * R_.tail(nc);
  Eigen::Map<Vec>(F + 2 * nq + nc, nc) = sc_.s4 * (jv_ + phi_t_);
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
  // F_y yS + F_ẏ ẏS from products with the model's blocks (no GGL matrix is assembled):
  //   F1: s₁ (q̇S − vS + Φ_qᵀ μS + H_μ qS)        F2: (K_t + H_λ) qS + Φ_qᵀ λS + C vS + M v̇S
  //   F3: s₃ Φ_q qS                               F4: s₄ (∂(Φ_q v)/∂q qS + Φ_q vS)
  // plus F_p d_i = ∂r/∂p d_i in F2.
  const int nq = nq_, nc = nc_, N = n_;
  const auto nv = static_cast<Eigen::Index>(rS.size());
  state_into(t, y, yp, st_);
  const State& s = st_;
  sq_.resize(nq, nv), sv_.resize(nq, nv), sa_.resize(nq, nv);
  for (Eigen::Index i = 0; i < nv; ++i) {
    sq_.col(i) = Eigen::Map<const Vec>(yS[i], nq);
    sv_.col(i) = Eigen::Map<const Vec>(yS[i] + nq, nq);
    sa_.col(i) = Eigen::Map<const Vec>(ypS[i] + nq, nq);
  }
  m_.mass_damping_product(s, p, sa_, sv_, mc_);  // M v̇S + C vS
  mu_ = Eigen::Map<const Vec>(y + 2 * nq + nc, nc);
  m_.constraint_hessian_product(t, s.q, mu_, sq_, hq_);               // H_μ qS
  m_.velocity_constraint_jacobian_product(t, s.q, s.v, sq_, vq_);     // ∂(Φ_q v)/∂q qS
  m_.iteration_matrix(s, p, Coefficients{0, 0, 1}, 1.0, 0.0, vals_);  // [K_t+H_λ Φ_qᵀ; Φ_q 0]
  const CscPattern& P = m_.pattern();
  for (Eigen::Index i = 0; i < nv; ++i) {
    const Eigen::Map<const Vec> ys(yS[i], N), yps(ypS[i], N);
    Eigen::Map<Vec> out(rS[i], N);
    auto o1 = out.head(nq), o2 = out.segment(nq, nq), o3 = out.segment(2 * nq, nc),
         o4 = out.tail(nc);
    o1 = yps.head(nq) - ys.segment(nq, nq) + hq_.col(i);  // s₁ applied below
    o2 = mc_.col(i);
    o3.setZero();
    o4 = vq_.col(i);
    const double* qS = yS[i];
    const double* vS = yS[i] + nq;
    const double* lS = yS[i] + 2 * nq;
    const double* mS = yS[i] + 2 * nq + nc;
    for (int j = 0; j < P.n; ++j)
      for (int k = P.col_ptr[j]; k < P.col_ptr[j + 1]; ++k) {
        const int r = P.row_ind[k];
        const double a = vals_[k];
        if (j < nq) {
          if (r < nq) {
            o2[r] += a * qS[j];  // K_t + H_λ
          } else {
            o3[r - nq] += a * qS[j];  // Φ_q
            o4[r - nq] += a * vS[j];
          }
        } else if (r < nq) {
          o2[r] += a * lS[j - nq];  // Φ_qᵀ
          o1[r] += a * mS[j - nq];
        }
      }
    o1 *= sc_.s1;
    o3 *= sc_.s3;
    o4 *= sc_.s4;
    m_.residual_param_derivative(s, p, dirs[i], dr_);
    o2 += dr_.head(nq);
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
  state_into(t, y, yp, st_);
  const State& s = st_;
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
  mu_ = Eigen::Map<const Vec>(y + 2 * nq + nc, nc);
  adj_col_ = xq;
  m_.constraint_hessian_product(t, s.q, mu_, adj_col_, adj_hx_);  // H_μ ξ_q
  adj_col_ = xm;
  m_.velocity_constraint_jacobian_transpose_product(t, s.q, s.v, adj_col_, adj_vx_);  // Vjᵀ ξ_μ
  Eigen::Map<Vec> r(rB, N);
  r.head(nq) =
      s1 * xid.head(nq) - (s1 * adj_hx_.col(0) + adj_yk_.head(nq) + s4 * adj_vx_.col(0)) + gq;
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
