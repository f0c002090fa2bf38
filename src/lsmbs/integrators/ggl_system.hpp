#pragma once
// GglSystem — the Gear–Gupta–Leimkuhler stabilized index-2 form of a Model as an implicit DAE
// F(t, y, ẏ) = 0 in y = (q, v, λ, μ) (sizes nq, nq, nc, nc):
//   F1 = s₁ (q̇ − v + Φ_qᵀ μ)                 (q̇ = v, projected on the velocity constraints)
//   F2 = M v̇ − g + Φ_qᵀ λ = r(q, v, v̇, λ)    (eq. 7 with k = 1, ζ = 0)
//   F3 = s₃ Φ
//   F4 = s₄ (Φ_q v + Φ_t)
// with its Jacobian F_y + c_j F_ẏ, the forward sensitivity residuals F_y y_p + F_ẏ ẏ_p + F_p and
// the adjoint residual, all from the model's blocks (M, C_t, K_t, Φ_q, the constraint Hessians).
// The scales s₁ = s₄ = κ h_out, s₃ = κ (κ the model's stiffness scale) make all rows force-like.
// μ is the multiplier of the velocity projection (zero on the exact solution), λ the physical
// multiplier. No SUNDIALS types: IdasGGL hands these functions to IDAS (idas_ggl.cpp), and the
// unit tests check them against central differences of the residual.
#include <span>

#include "lsmbs/mbs/model.hpp"

namespace lsmbs {

class GglSystem {
 public:
  struct Scales {
    double s1 = 1, s3 = 1, s4 = 1;
  };
  explicit GglSystem(const Model& model)
      : m_(model), nq_(model.nq()), nc_(model.nc()), n_(2 * model.nq() + 2 * model.nc()) {}

  const Model& model() const { return m_; }
  int nq() const { return nq_; }
  int nc() const { return nc_; }
  int size() const { return n_; }  ///< 2 nq + 2 nc
  const Scales& scales() const { return sc_; }
  void set_scales(const Scales& s) { sc_ = s; }

  /// The model's state (t, q, v, λ, a = v̇) of y, ẏ.
  State state(double t, const double* y, const double* yp) const;
  /// The same into s (no allocation once s has its sizes).
  void state_into(double t, const double* y, const double* yp, State& s) const;

  /// F(t, y, ẏ) (size N) at the parameters p. False when the model's residual is not finite.
  bool residual(const ModelParams& p, double t, const double* y, const double* yp, double* F);
  /// F_y + c_j F_ẏ (N × N, compressed; the pattern does not depend on the values: explicit zeros
  /// are kept).
  SpMat jacobian(const ModelParams& p, double t, double cj, const double* y, const double* yp);
  /// r_i = F_y yS_i + F_ẏ ẏS_i + F_p d_i for each parameter direction d_i (F_p: only F2 depends
  /// on the parameters, F_p = ∂r/∂p). The derivatives are taken at p. Products with the model's
  /// blocks, element by element and on the model's pattern: no matrix is assembled.
  void sensitivity_residual(const ModelParams& p, double t, const double* y, const double* yp,
                            std::span<const ParamDirection> dirs, std::span<const double* const> yS,
                            std::span<const double* const> ypS, std::span<double* const> rS);
  /// Residual of the adjoint DAE of a quadrature Q = ∫ g(y, ẏ) dt for the multipliers ξ = (ξ_q,
  /// ξ_v, ξ_λ, ξ_μ) of the rows F1–F4: d/dt(F_ẏᵀ ξ) − F_yᵀ ξ + ∂g/∂y, with F_ẏ = diag(s₁ I, M(q),
  /// 0, 0); gq = ∂g/∂q, gv = ∂g/∂q̇ at the forward state (t, y, ẏ). Written out:
  ///   q:  s₁ ξ̇_q − (s₁ H_μ ξ_q + K_tᵀ ξ_v + s₃ Φ_qᵀ ξ_λ + s₄ (∂(Φ_q v)/∂q)ᵀ ξ_μ) + ∂g/∂q
  ///   v:  M ξ̇_v + Ṁ ξ_v − (−s₁ ξ_q + C_tᵀ ξ_v + s₄ Φ_qᵀ ξ_μ) + ∂g/∂q̇
  ///   λ:  −Φ_q ξ_v,   μ:  −s₁ Φ_q ξ_q
  /// (H_μ = Σ μ_i ∂²Φ_i/∂q²). It has the GGL's Hessenberg index-2 structure: ξ_λ and ξ_μ are
  /// algebraic and act on ξ_q, ξ_v through Φ_qᵀ. False when the result is not finite.
  bool adjoint_residual(const ModelParams& p, double t, const double* y, const double* yp,
                        const double* xi, const double* xid, const Vec& gq, const Vec& gv,
                        double* rB);

 private:
  // out = Sᵀ x for S given by its values v on the model's pattern (no matrix assembled).
  void pattern_transpose_product(const std::vector<double>& v, const Vec& x, Vec& out) const;

  const Model& m_;
  const int nq_, nc_, n_;
  Scales sc_;
  // workspace: residual and sensitivity residuals allocate nothing once sized
  State st_;
  Vec R_, phi_t_, gamma_, dr_, mu_, jv_, jtmu_;
  Mat sq_, sv_, sa_, mc_, hq_, vq_;
  std::vector<double> vals_;
  Vec adj_x_, adj_yk_, adj_yc_, adj_yq_, adj_mw_;
  Mat adj_a_, adj_zero_, adj_ma_, adj_col_, adj_hx_, adj_vx_;
};

}  // namespace lsmbs
