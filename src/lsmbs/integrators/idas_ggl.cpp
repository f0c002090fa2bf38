#include "lsmbs/integrators/idas_ggl.hpp"

#include <idas/idas.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <chrono>
#include <cmath>
#include <algorithm>
#include <map>
#include <vector>

#include "lsmbs/integrators/generalized_alpha.hpp"
#include "lsmbs/integrators/initial_state.hpp"
#include "lsmbs/linalg/sparse_lu.hpp"

#include <Eigen/SparseLU>

namespace lsmbs {

IdasOptions IdasOptions::reference() {
  IdasOptions o;
  o.rtol = 1e-9;
  o.atol = 1e-9;
  return o;
}

nlohmann::json IdasOptions::to_json() const {
  return {{"rtol", rtol}, {"atol", atol}, {"h_out", h_out}, {"t_end", t_end}, {"max_steps", max_steps},
          {"max_order", max_order > 0 ? nlohmann::json(max_order) : nlohmann::json("auto")},
          {"klu_pivot_tolerance", klu_pivot_tolerance},
          {"corrector", staggered ? "staggered" : "simultaneous"},
          {"error_test", error_test == ErrorTest::kPositions                ? "positions"
                         : error_test == ErrorTest::kPositionsAndVelocities ? "positions+velocities"
                                                                            : "auto"},
          {"sensitivity_residual", analytic_sensitivity_residual ? "analytic" : "idas_difference_quotients"},
          {"adjoint_checkpoint_steps", adjoint_checkpoint_steps}};
}

nlohmann::json IdasStats::to_json() const {
  nlohmann::json j = {{"ok", ok}, {"message", message}, {"steps", steps}, {"residual_evaluations", residual_evaluations},
          {"jacobian_evaluations", jacobian_evaluations}, {"nonlinear_iterations", nonlinear_iterations},
          {"error_test_failures", error_test_failures}, {"nonlinear_convergence_failures", nonlinear_convergence_failures},
          {"sensitivity_residual_evaluations", sensitivity_residual_evaluations}, {"wall_seconds", wall_seconds},
          {"error_test", error_test}, {"max_order", max_order}, {"massless_velocities", massless_velocities}};
  if (adjoint_problems > 0)
    j["adjoint"] = {{"backward_problems", adjoint_problems}, {"steps", adjoint_steps},
                    {"residual_evaluations", adjoint_residual_evaluations},
                    {"jacobian_evaluations", adjoint_jacobian_evaluations}, {"checkpoints", checkpoints},
                    {"wall_seconds", adjoint_wall_seconds}};
  return j;
}

struct IdasGGL::Impl {
  const Model& m;
  const ModelParams& nominal;
  IdasOptions o;
  int nq, nc, N;
  double s1 = 1, s3 = 1, s4 = 1;
  // design-variable parameters for IDAS difference quotients
  const Parameterization* design = nullptr;
  Vec p_nominal;
  std::vector<double> p;  // the array IDAS perturbs
  std::map<std::vector<double>, ModelParams> perturbed;
  std::vector<ParamDirection> dirs;
  // workspace
  Vec R, phi_t, gamma;
  std::vector<double> vals;
  // quadratures
  IdasQuadrature* quad = nullptr;
  Mat qs_dq, qs_dv, qs_da, qs_dl, qs_dg;

  Impl(const Model& model, const ModelParams& params, IdasOptions opt)
      : m(model), nominal(params), o(opt), nq(model.nq()), nc(model.nc()), N(2 * model.nq() + 2 * model.nc()) {}

  const ModelParams& params() {
    if (!design) return nominal;
    bool same = true;
    for (size_t i = 0; i < p.size(); ++i) same &= p[i] == p_nominal[static_cast<Eigen::Index>(i)];
    if (same) return nominal;
    auto it = perturbed.find(p);
    if (it == perturbed.end()) {
      ModelParams mp = nominal;
      design->apply(Eigen::Map<const Vec>(p.data(), static_cast<Eigen::Index>(p.size())), mp);
      it = perturbed.emplace(p, std::move(mp)).first;
    }
    return it->second;
  }

  State state(double t, const double* y, const double* yp) const {
    State s;
    s.t = t;
    s.q = Eigen::Map<const Vec>(y, nq);
    s.v = Eigen::Map<const Vec>(y + nq, nq);
    s.lambda = Eigen::Map<const Vec>(y + 2 * nq, nc);
    s.a = Eigen::Map<const Vec>(yp + nq, nq);
    return s;
  }

  int residual(double t, const double* y, const double* yp, double* F) {
    const ModelParams& prm = params();
    const State s = state(t, y, yp);
    m.residual(s, prm, 1.0, 0.0, R);
    if (!R.allFinite()) return 1;  // recoverable: IDAS retries with a smaller step
    const SpMat J = m.constraint_jacobian(t, s.q, prm);
    m.constraint_time_terms(t, s.q, s.v, prm, phi_t, gamma);
    const Eigen::Map<const Vec> qd(yp, nq), mu(y + 2 * nq + nc, nc);
    Eigen::Map<Vec>(F, nq) = s1 * (qd - s.v + J.transpose() * mu);
    Eigen::Map<Vec>(F + nq, nq) = R.head(nq);
    Eigen::Map<Vec>(F + 2 * nq, nc) = s3 * R.tail(nc);
    Eigen::Map<Vec>(F + 2 * nq + nc, nc) = s4 * (J * s.v + phi_t);
    return 0;
  }

  // F_y + cj F_ẏ as an Eigen sparse matrix (pattern fixed: explicit zeros kept).
  SpMat jacobian(double t, double cj, const double* y, const double* yp) {
    const ModelParams& prm = params();
    const State s = state(t, y, yp);
    m.iteration_matrix(s, prm, Coefficients{0, 0, 1}, 1.0, 0.0, vals);
    const SpMat A = m.assembler().to_sparse(vals);  // [K + H(λ)  Φ_qᵀ ; Φ_q  0]
    m.iteration_matrix(s, prm, Coefficients{cj, 1, 0}, 1.0, 0.0, vals);
    const SpMat B = m.assembler().to_sparse(vals);  // q-block: cj M + C
    const Vec mu = Eigen::Map<const Vec>(y + 2 * nq + nc, nc);
    const SpMat Hmu = m.constraint_hessian(t, s.q, mu);
    const SpMat Vj = m.velocity_constraint_jacobian(t, s.q, s.v);
    std::vector<Eigen::Triplet<double>> tr;
    tr.reserve(A.nonZeros() * 3 + Hmu.nonZeros() + Vj.nonZeros() + 2 * nq);
    const int oq = 0, ov = nq, ol = 2 * nq, om = 2 * nq + nc;  // column offsets
    const int r1 = 0, r2 = nq, r3 = 2 * nq, r4 = 2 * nq + nc;  // row offsets
    for (int i = 0; i < nq; ++i) {
      tr.emplace_back(r1 + i, oq + i, s1 * cj);
      tr.emplace_back(r1 + i, ov + i, -s1);
    }
    for (int k = 0; k < Hmu.outerSize(); ++k)
      for (SpMat::InnerIterator it(Hmu, k); it; ++it) tr.emplace_back(r1 + it.row(), oq + it.col(), s1 * it.value());
    for (int k = 0; k < A.outerSize(); ++k)
      for (SpMat::InnerIterator it(A, k); it; ++it) {
        const int i = static_cast<int>(it.row()), j = static_cast<int>(it.col());
        if (i < nq && j < nq) tr.emplace_back(r2 + i, oq + j, it.value());
        else if (i < nq) tr.emplace_back(r2 + i, ol + (j - nq), it.value());            // Φ_qᵀ → λ
        else if (j < nq) {
          tr.emplace_back(r3 + (i - nq), oq + j, s3 * it.value());                      // Φ_q → F3
          tr.emplace_back(r4 + (i - nq), ov + j, s4 * it.value());                      // Φ_q → F4 (v)
          tr.emplace_back(r1 + j, om + (i - nq), s1 * it.value());                      // Φ_qᵀ → F1 (μ)
        }
      }
    for (int k = 0; k < B.outerSize(); ++k)
      for (SpMat::InnerIterator it(B, k); it; ++it)
        if (it.row() < nq && it.col() < nq) tr.emplace_back(r2 + it.row(), ov + it.col(), it.value());
    for (int k = 0; k < Vj.outerSize(); ++k)
      for (SpMat::InnerIterator it(Vj, k); it; ++it) tr.emplace_back(r4 + it.row(), oq + it.col(), s4 * it.value());
    SpMat Jm(N, N);
    Jm.setFromTriplets(tr.begin(), tr.end());
    Jm.makeCompressed();
    return Jm;
  }

  int quad_rhs(double t, const double* y, const double* yp, double* g) {
    quad->integrand(state(t, y, yp), params(), g);
    return 0;
  }

  int quad_sens_rhs(double t, const double* y, const double* yp, const std::vector<const double*>& yS,
                    const std::vector<const double*>& ypS, const std::vector<double*>& gS) {
    const int nv = static_cast<int>(yS.size());
    qs_dq.resize(nq, nv), qs_dv.resize(nq, nv), qs_da.resize(nq, nv), qs_dl.resize(nc, nv);
    for (int i = 0; i < nv; ++i) {
      const Eigen::Map<const Vec> ys(yS[i], N), yps(ypS[i], N);
      qs_dq.col(i) = ys.head(nq);
      qs_dv.col(i) = ys.segment(nq, nq);
      qs_dl.col(i) = ys.segment(2 * nq, nc);
      qs_da.col(i) = yps.segment(nq, nq);
    }
    quad->integrand_sensitivity(state(t, y, yp), nominal, qs_dq, qs_dv, qs_da, qs_dl, qs_dg);
    for (int i = 0; i < nv; ++i) Eigen::Map<Vec>(gS[i], quad->size()) = qs_dg.col(i);
    return 0;
  }

  // Analytic sensitivity residuals F_y yS + F_ẏ ẏS + F_p (all variables).
  int sens_residual(double t, const double* y, const double* yp, const std::vector<const double*>& yS,
                    const std::vector<const double*>& ypS, const std::vector<double*>& rS) {
    const State s = state(t, y, yp);
    m.iteration_matrix(s, nominal, Coefficients{0, 0, 0}, 1.0, 0.0, vals);
    const std::vector<double> v0 = vals;
    m.iteration_matrix(s, nominal, Coefficients{1, 0, 0}, 1.0, 0.0, vals);
    std::vector<double> vm = vals;
    m.iteration_matrix(s, nominal, Coefficients{0, 1, 0}, 1.0, 0.0, vals);
    std::vector<double> vc = vals;
    for (size_t k = 0; k < vals.size(); ++k) vm[k] -= v0[k], vc[k] -= v0[k];
    const SpMat M = m.assembler().to_sparse(vm).topLeftCorner(nq, nq), C = m.assembler().to_sparse(vc).topLeftCorner(nq, nq);
    const SpMat Jy = jacobian(t, 0.0, y, yp);  // F_y (cj = 0)
    Vec dr;
    for (size_t i = 0; i < rS.size(); ++i) {
      const Eigen::Map<const Vec> ys(yS[i], N), yps(ypS[i], N);
      Eigen::Map<Vec> out(rS[i], N);
      out = Jy * ys;
      out.head(nq) += s1 * yps.head(nq);
      out.segment(nq, nq) += M * yps.segment(nq, nq);
      (void)C;
      m.residual_param_derivative(s, nominal, dirs[i], dr);
      out.segment(nq, nq) += dr.head(nq);
    }
    return 0;
  }

  // ---- adjoint (run_adjoint). ξ = (ξ_q, ξ_v, ξ_λ, ξ_μ) are the multipliers of the rows F1–F4.
  // With F_ẏ = diag(s₁ I, M(q), 0, 0), the adjoint DAE of Q_k = ∫ g_k dt is
  //   q:  s₁ ξ̇_q − (s₁ H_μ ξ_q + K_tᵀ ξ_v + s₃ Φ_qᵀ ξ_λ + s₄ (∂(Φ_q v)/∂q)ᵀ ξ_μ) + ∂g/∂q = 0
  //   v:  M ξ̇_v + Ṁ ξ_v − (−s₁ ξ_q + Cᵀ ξ_v + s₄ Φ_qᵀ ξ_μ) + ∂g/∂q̇ = 0
  //   λ:  −Φ_q ξ_v = 0,   μ:  −s₁ Φ_q ξ_q = 0
  // (the bracket is F_yᵀ ξ). It has the GGL's Hessenberg index-2 structure: ξ_λ and ξ_μ are
  // algebraic and appear in the differential rows through Φ_qᵀ, the constraints act on ξ_q, ξ_v.
  Vec adj_gq, adj_gv, adj_mw, adj_dr;
  Eigen::RowVectorXd adj_gp;
  Mat adj_a, adj_zero, adj_ma;
  std::string adj_error;  // why a backward callback failed (reported by run_adjoint)

  bool adjoint_integrand(int k, const State& s) {
    return quad->integrand_gradient(k, s, nominal, adj_gq, adj_gv, adj_gp, adj_error);
  }

  // y = Sᵀ x for S given by its values on the model's pattern (no assembly of a matrix)
  void pattern_transpose_product(const std::vector<double>& v, const Vec& x, Vec& out) const {
    const CscPattern& P = m.pattern();
    out.resize(P.n);
    for (int j = 0; j < P.n; ++j) {
      double acc = 0;
      for (int k = P.col_ptr[j]; k < P.col_ptr[j + 1]; ++k) acc += v[k] * x[P.row_ind[k]];
      out[j] = acc;
    }
  }
  Vec adj_x, adj_yk, adj_yc, adj_yq;

  int adjoint_residual(int k, double t, const double* y, const double* yp, const double* yB, const double* ypB,
                       double* rB) {
    const State s = state(t, y, yp);
    if (!adjoint_integrand(k, s)) return -1;
    const Eigen::Map<const Vec> xi(yB, N), xid(ypB, N);
    const auto xq = xi.head(nq), xv = xi.segment(nq, nq), xl = xi.segment(2 * nq, nc), xm = xi.tail(nc);
    // F_yᵀ ξ from transposed products with the model's blocks on its pattern:
    //   [K_t Φ_qᵀ; Φ_q 0]ᵀ [ξ_v; s₃ξ_λ] = [K_tᵀξ_v + s₃Φ_qᵀξ_λ; Φ_q ξ_v]
    //   [C_t Φ_qᵀ; Φ_q 0]ᵀ [ξ_v; s₄ξ_μ] = [C_tᵀξ_v + s₄Φ_qᵀξ_μ; Φ_q ξ_v],  and Φ_q ξ_q
    m.iteration_matrix(s, nominal, Coefficients{0, 0, 1}, 1.0, 0.0, vals);
    adj_x.resize(nq + nc);
    adj_x << xv, s3 * xl;
    pattern_transpose_product(vals, adj_x, adj_yk);
    m.iteration_matrix(s, nominal, Coefficients{0, 1, 0}, 1.0, 0.0, vals);
    adj_x << xv, s4 * xm;
    pattern_transpose_product(vals, adj_x, adj_yc);
    adj_x << xq, Vec::Zero(nc);
    pattern_transpose_product(vals, adj_x, adj_yq);
    const SpMat Hmu = m.constraint_hessian(t, s.q, Eigen::Map<const Vec>(y + 2 * nq + nc, nc));
    const SpMat Vj = m.velocity_constraint_jacobian(t, s.q, s.v);
    Eigen::Map<Vec> r(rB, N);
    r.head(nq) = s1 * xid.head(nq) - (s1 * (Hmu * xq) + adj_yk.head(nq) + s4 * (Vj.transpose() * xm)) + adj_gq;
    adj_a = xid.segment(nq, nq);
    adj_zero.setZero(nq, 1);
    m.mass_damping_product(s, nominal, adj_a, adj_zero, adj_ma);  // M ξ̇_v (C·0)
    m.mass_rate_product(s, nominal, xv, adj_mw);                  // Ṁ ξ_v
    r.segment(nq, nq) = adj_ma.col(0) + adj_mw - (-s1 * xq + adj_yc.head(nq)) + adj_gv;
    r.segment(2 * nq, nc) = -adj_yk.tail(nc);
    r.tail(nc) = -s1 * adj_yq.tail(nc);
    return r.allFinite() ? 0 : 1;
  }

  // rhsQB = ξᵀ F_p − ∂g/∂p: integrated from t_b back to t0 it gives ∫_{t0}^{t_b} (∂g/∂p − ξᵀF_p) dt.
  int adjoint_quadrature(int k, double t, const double* y, const double* yp, const double* yB, double* qB) {
    const State s = state(t, y, yp);
    if (!adjoint_integrand(k, s)) return -1;
    const Eigen::Map<const Vec> xv(yB + nq, nq);
    for (size_t i = 0; i < dirs.size(); ++i) {
      m.residual_param_derivative(s, nominal, dirs[i], adj_dr);  // F_p: only F2 depends on p
      qB[i] = xv.dot(adj_dr.head(nq)) - adj_gp[static_cast<Eigen::Index>(i)];
    }
    return 0;
  }

  // Consistent final values at t_b: ξ_q = ξ_v = 0 (the boundary term ξᵀF_ẏ y_p vanishes), and the
  // algebraic ξ_λ, ξ_μ with ξ̇_q, ξ̇_v from the hidden constraints Φ_q ξ̇_v = Φ_q ξ̇_q = 0 (the
  // time derivatives of rows λ, μ at ξ = 0):
  //   [M Φ_qᵀ; Φ_q 0] [ξ̇_v; −s₄ ξ_μ] = [−∂g/∂q̇; 0]
  //   [I Φ_qᵀ; Φ_q 0] [s₁ ξ̇_q; −s₃ ξ_λ] = [s₄ (∂(Φ_q v)/∂q)ᵀ ξ_μ − ∂g/∂q; 0]
  // Also returns scales of the four blocks and of the gradient for the absolute tolerances.
  bool adjoint_final_values(int k, double tb, const Vec& y, const Vec& yp, Vec& xi, Vec& xid, double scale[5]) {
    const State s = state(tb, y.data(), yp.data());
    if (!adjoint_integrand(k, s)) return false;
    m.iteration_matrix(s, nominal, Coefficients{1, 0, 0}, 1.0, 0.0, vals);
    const SpMat SM = m.assembler().to_sparse(vals);
    const SpMat Jc = m.constraint_jacobian(tb, s.q, nominal);
    std::vector<Eigen::Triplet<double>> tr;
    for (int i = 0; i < nq; ++i) tr.emplace_back(i, i, 1.0);
    for (int c = 0; c < Jc.outerSize(); ++c)
      for (SpMat::InnerIterator it(Jc, c); it; ++it) {
        tr.emplace_back(nq + it.row(), it.col(), it.value());
        tr.emplace_back(it.col(), nq + it.row(), it.value());
      }
    SpMat SI(nq + nc, nq + nc);
    SI.setFromTriplets(tr.begin(), tr.end());
    Eigen::SparseLU<SpMat> lu_m, lu_i;
    lu_m.compute(SM);
    lu_i.compute(SI);
    if (lu_m.info() != Eigen::Success || lu_i.info() != Eigen::Success) {
      adj_error = "singular constraint system for the adjoint final values at t = " + std::to_string(tb);
      return false;
    }
    Vec rhs = Vec::Zero(nq + nc);
    rhs.head(nq) = -adj_gv;
    Vec x = lu_m.solve(rhs);
    xi.setZero(N);
    xid.setZero(N);
    xid.segment(nq, nq) = x.head(nq);
    xi.tail(nc) = -x.tail(nc) / s4;
    const SpMat Vj = m.velocity_constraint_jacobian(tb, s.q, s.v);
    rhs.head(nq) = s4 * (Vj.transpose() * xi.tail(nc)) - adj_gq;
    rhs.tail(nc).setZero();
    x = lu_i.solve(rhs);
    xid.head(nq) = x.head(nq) / s1;
    xi.segment(2 * nq, nc) = -x.tail(nc) / s3;
    // Block scales: ξ grows from zero at t_b like ξ̇ (t_b − t0); ξ_q and ξ_v drive each other
    // through M ξ̇_v ≈ −s₁ ξ_q (m: largest diagonal mass), the algebraic blocks balance them.
    const double W = std::max(tb - t_start, 1e-300);
    double mmax = 0;
    for (int i = 0; i < nq; ++i) mmax = std::max(mmax, std::abs(SM.coeff(i, i)));
    double sq = xid.head(nq).lpNorm<Eigen::Infinity>() * W, sv = xid.segment(nq, nq).lpNorm<Eigen::Infinity>() * W;
    sv = std::max(sv, s1 * sq * W / mmax);
    sq = std::max(sq, mmax * sv / (s1 * W));
    if (!(sq > 0)) sq = sv = 1;  // g independent of the state: ξ ≡ 0
    scale[0] = sq;
    scale[1] = sv;
    scale[2] = std::max(xi.segment(2 * nq, nc).lpNorm<Eigen::Infinity>(), s1 * sq / (s3 * W));
    scale[3] = std::max(xi.tail(nc).lpNorm<Eigen::Infinity>(), mmax * sv / (s4 * W));
    // gradient scale ~ ξ_v × |F_p| × (t_b − t0)
    double fp = 0;
    for (const auto& d : dirs) {
      m.residual_param_derivative(s, nominal, d, adj_dr);
      fp = std::max(fp, adj_dr.head(nq).lpNorm<Eigen::Infinity>());
    }
    scale[4] = sv * (fp > 0 ? fp : 1.0) * W;
    return true;
  }
  double t_start = 0;
  SUNLinearSolver fresh_klu = nullptr;  // re-analyzed at every Jacobian (adjoint runs, see run_mode)
};

namespace {

int res_tramp(realtype t, N_Vector y, N_Vector yp, N_Vector rr, void* ud) {
  return static_cast<IdasGGL::Impl*>(ud)->residual(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), N_VGetArrayPointer(rr));
}

// Copies a compressed CSC matrix into a SUNDIALS sparse matrix.
void copy_to(const SpMat& A, SUNMatrix J) {
  if (SM_NNZ_S(J) < A.nonZeros()) SUNSparseMatrix_Reallocate(J, A.nonZeros());
  sunindextype* cp = SM_INDEXPTRS_S(J);
  sunindextype* ri = SM_INDEXVALS_S(J);
  realtype* d = SM_DATA_S(J);
  for (int c = 0; c <= A.cols(); ++c) cp[c] = A.outerIndexPtr()[c];
  for (Eigen::Index k = 0; k < A.nonZeros(); ++k) ri[k] = A.innerIndexPtr()[k], d[k] = A.valuePtr()[k];
}

int jac_tramp(realtype t, realtype cj, N_Vector y, N_Vector yp, N_Vector, SUNMatrix J, void* ud, N_Vector, N_Vector,
              N_Vector) {
  auto* im = static_cast<IdasGGL::Impl*>(ud);
  copy_to(im->jacobian(t, cj, N_VGetArrayPointer(y), N_VGetArrayPointer(yp)), J);
  if (im->fresh_klu) SUNLinSol_KLUReInit(im->fresh_klu, J, SM_NNZ_S(J), SUNKLU_REINIT_PARTIAL);
  return 0;
}

int sens_tramp(int Ns, realtype t, N_Vector y, N_Vector yp, N_Vector, N_Vector* yS, N_Vector* ypS, N_Vector* rS, void* ud,
               N_Vector, N_Vector, N_Vector) {
  std::vector<const double*> a(Ns), b(Ns);
  std::vector<double*> c(Ns);
  for (int i = 0; i < Ns; ++i) a[i] = N_VGetArrayPointer(yS[i]), b[i] = N_VGetArrayPointer(ypS[i]), c[i] = N_VGetArrayPointer(rS[i]);
  return static_cast<IdasGGL::Impl*>(ud)->sens_residual(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), a, b, c);
}

int quad_tramp(realtype t, N_Vector y, N_Vector yp, N_Vector rQ, void* ud) {
  return static_cast<IdasGGL::Impl*>(ud)->quad_rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), N_VGetArrayPointer(rQ));
}

int quad_sens_tramp(int Ns, realtype t, N_Vector y, N_Vector yp, N_Vector* yS, N_Vector* ypS, N_Vector, N_Vector* rQS,
                    void* ud, N_Vector, N_Vector, N_Vector) {
  std::vector<const double*> a(Ns), b(Ns);
  std::vector<double*> c(Ns);
  for (int i = 0; i < Ns; ++i) a[i] = N_VGetArrayPointer(yS[i]), b[i] = N_VGetArrayPointer(ypS[i]), c[i] = N_VGetArrayPointer(rQS[i]);
  return static_cast<IdasGGL::Impl*>(ud)->quad_sens_rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), a, b, c);
}

// One backward problem of an adjoint run: dQ_k(t_b)/dp. Owns its vectors and linear solver;
// its IDAS memory belongs to the forward one (freed by IDAFree).
struct Backward {
  IdasGGL::Impl* im = nullptr;
  int k = 0, which = -1;
  double tb = 0;
  N_Vector yB = nullptr, ypB = nullptr, idB = nullptr, atolB = nullptr, qB = nullptr;
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  ~Backward() {
    if (LS) SUNLinSolFree(LS);
    if (A) SUNMatDestroy(A);
    for (N_Vector v : {yB, ypB, idB, atolB, qB})
      if (v) N_VDestroy(v);
  }
};

int res_b_tramp(realtype t, N_Vector y, N_Vector yp, N_Vector yB, N_Vector ypB, N_Vector rB, void* ud) {
  auto* b = static_cast<Backward*>(ud);
  return b->im->adjoint_residual(b->k, t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), N_VGetArrayPointer(yB),
                                 N_VGetArrayPointer(ypB), N_VGetArrayPointer(rB));
}

// ∂resB/∂ξ + c_jB ∂resB/∂ξ̇ = −(F_y − c_jB F_ẏ)ᵀ: the forward Jacobian at c_j = −c_jB, transposed
// and negated (Ṁ, the derivative of Ṁ ξ_v, is left out: O(|q̇|) against c_jB M).
int jac_b_tramp(realtype t, realtype cjB, N_Vector y, N_Vector yp, N_Vector, N_Vector, N_Vector, SUNMatrix J, void* ud,
                N_Vector, N_Vector, N_Vector) {
  auto* b = static_cast<Backward*>(ud);
  const SpMat A = b->im->jacobian(t, -cjB, N_VGetArrayPointer(y), N_VGetArrayPointer(yp));
  SpMat At = -SpMat(A.transpose());
  At.makeCompressed();
  copy_to(At, J);
  return 0;
}

int quad_b_tramp(realtype t, N_Vector y, N_Vector yp, N_Vector yB, N_Vector, N_Vector qB, void* ud) {
  auto* b = static_cast<Backward*>(ud);
  return b->im->adjoint_quadrature(b->k, t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), N_VGetArrayPointer(yB),
                                   N_VGetArrayPointer(qB));
}

// RAII for the SUNDIALS objects of one run.
struct Sundials {
  SUNContext ctx = nullptr;
  void* mem = nullptr;
  N_Vector y = nullptr, yp = nullptr, id = nullptr, atol = nullptr, dky = nullptr, yQ = nullptr;
  N_Vector* yS = nullptr;
  N_Vector* yQS = nullptr;
  N_Vector* ypS = nullptr;
  N_Vector* dkyS = nullptr;
  int ns = 0;
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  std::vector<std::unique_ptr<Backward>> back;  // backward problems (adjoint runs)
  ~Sundials() {
    if (mem) IDAFree(&mem);  // frees the backward IDAS memories too
    back.clear();
    if (LS) SUNLinSolFree(LS);
    if (A) SUNMatDestroy(A);
    for (N_Vector v : {y, yp, id, atol, dky, yQ})
      if (v) N_VDestroy(v);
    if (yQS) N_VDestroyVectorArray(yQS, ns);
    if (yS) N_VDestroyVectorArray(yS, ns);
    if (ypS) N_VDestroyVectorArray(ypS, ns);
    if (dkyS) N_VDestroyVectorArray(dkyS, ns);
    if (ctx) SUNContext_Free(&ctx);
  }
};

// Adjoint runs: Q and the forward state at a breakpoint (or the final time).
struct Breakpoint {
  double t;
  Vec Q, y, yp;
};

// The backward pass of an adjoint run: one backward problem per (quadrature k, breakpoint t_b)
// asked for, all integrated to t0 by one IDASolveB; fills dQ[b] (rows not asked for: NaN).
// Returns an empty string or the reason of a failure.
std::string backward_pass(Sundials& sd, IdasGGL::Impl& im, const std::vector<Breakpoint>& breaks, double t0,
                          bool positions_only, int max_order, long nnz, IdasStats& st, std::vector<Mat>& dQ) {
  const int nq = im.nq, nc = im.nc, N = im.N, nQ = im.quad->size(), nv = static_cast<int>(im.dirs.size());
  Vec xi, xid;
  double scale[5];
  dQ.assign(breaks.size(), Mat::Constant(nQ, nv, NAN));
  // Creates the backward problems of breakpoint b (when the backward pass has reached it).
  auto create = [&](size_t b) -> std::string {
    for (int k = 0; k < nQ; ++k) {
      const double tb = breaks[b].t;
      if (!(tb > t0) || !im.quad->needs_gradient(k, tb)) continue;
      if (!im.adjoint_final_values(k, tb, breaks[b].y, breaks[b].yp, xi, xid, scale))
        return "adjoint final values of quadrature " + std::to_string(k) + ": " + im.adj_error;
      auto bp = std::make_unique<Backward>();
      Backward& B = *bp;
      sd.back.push_back(std::move(bp));
      B.im = &im, B.k = k, B.tb = tb;
      B.yB = N_VNew_Serial(N, sd.ctx);
      B.ypB = N_VNew_Serial(N, sd.ctx);
      B.idB = N_VNew_Serial(N, sd.ctx);
      B.atolB = N_VNew_Serial(N, sd.ctx);
      B.qB = N_VNew_Serial(nv, sd.ctx);
      Eigen::Map<Vec>(N_VGetArrayPointer(B.yB), N) = xi;
      Eigen::Map<Vec>(N_VGetArrayPointer(B.ypB), N) = xid;
      Eigen::Map<Vec>(N_VGetArrayPointer(B.idB), N) << Vec::Ones(2 * nq), Vec::Zero(2 * nc);
      // Error test: ξ_v (position-like) always; ξ_q (velocity-like: s₁ ξ̇_q = K_tᵀ ξ_v …,
      // M ξ̇_v = −s₁ ξ_q …) only when the forward test has velocities (rigid models); the gradient
      // quadratures too. The adjoint load ∂g/∂q switches on at t_b like a step load and excites
      // every undamped structural mode of ξ_v at the amplitude of its static response, which
      // costs many backward steps on flexible models. Taking ξ_v out of the test (quadratures
      // only) was 9× cheaper on the 12 × 2 test arm but 2 % wrong on the robot arm's mesh over
      // 0.4 s and 20 % over 2.5 s against central differences of IDAS runs: the quadrature's local
      // error estimate does not see the accumulated error of ξ_v.
      const double off = 1e30;  // weight ≈ 0: out of the error test
      Eigen::Map<Vec>(N_VGetArrayPointer(B.atolB), N) << Vec::Constant(nq, positions_only ? off : im.o.atol * scale[0]),
          Vec::Constant(nq, im.o.atol * scale[1]), Vec::Constant(nc, im.o.atol * scale[2]),
          Vec::Constant(nc, im.o.atol * scale[3]);
      N_VConst(0.0, B.qB);
      if (IDACreateB(sd.mem, &B.which) || IDAInitB(sd.mem, B.which, res_b_tramp, tb, B.yB, B.ypB) ||
          IDASVtolerancesB(sd.mem, B.which, im.o.rtol, B.atolB) || IDASetUserDataB(sd.mem, B.which, &B) ||
          IDASetIdB(sd.mem, B.which, B.idB) || IDASetSuppressAlgB(sd.mem, B.which, SUNTRUE) ||
          IDASetMaxOrdB(sd.mem, B.which, max_order) || IDASetMaxNumStepsB(sd.mem, B.which, im.o.max_steps))
        return "IDAS backward problem set-up failed";
      B.A = SUNSparseMatrix(N, N, nnz, CSC_MAT, sd.ctx);
      B.LS = B.A ? SUNLinSol_KLU(B.yB, B.A, sd.ctx) : nullptr;
      if (B.LS) SUNLinSol_KLUGetCommon(B.LS)->tol = im.o.klu_pivot_tolerance;
      if (!B.LS || IDASetLinearSolverB(sd.mem, B.which, B.LS, B.A) || IDASetJacFnB(sd.mem, B.which, jac_b_tramp) ||
          IDAQuadInitB(sd.mem, B.which, quad_b_tramp, B.qB))
        return "IDAS backward linear solver or quadrature set-up failed";
      // the gradient quadratures are in the error test (absolute part: atol × gradient scale)
      if (IDAQuadSStolerancesB(sd.mem, B.which, im.o.rtol, im.o.atol * scale[4]) ||
          IDASetQuadErrConB(sd.mem, B.which, SUNTRUE))
        return "IDAS backward quadrature tolerances rejected";
    }
    return "";
  };
  // Backward in chunks (64 over the span, plus every breakpoint). The a-priori gradient scale
  // (scale[4]) can be orders of magnitude too large (300× on the flexible test arm); after each
  // chunk the absolute tolerance of each gradient quadrature becomes atol × the largest |dQ/dp|
  // accumulated so far. (With the a-priori scale alone the full robot arm's gradient at rtol 1e-8
  // was 10× too small.) A breakpoint's problems are created when the pass reaches it: IDASolveB
  // requires every existing backward problem to lie ahead of tBout.
  double t_hi = t0;
  for (const auto& bp : breaks) t_hi = std::max(t_hi, bp.t);
  constexpr int kChunks = 64;
  std::vector<double> stops;
  for (int c = 0; c <= kChunks; ++c) stops.push_back(c == kChunks ? t0 : t_hi - (t_hi - t0) * c / kChunks);
  for (const auto& bp : breaks) stops.push_back(bp.t);
  std::sort(stops.begin(), stops.end(), std::greater<>());
  const double eps = 1e-12 * std::max(1.0, std::abs(t_hi));
  stops.erase(std::unique(stops.begin(), stops.end(), [&](double a, double b) { return std::abs(a - b) <= eps; }),
              stops.end());
  im.adj_error.clear();
  int flag = 0;
  for (size_t c = 0; c < stops.size() && flag >= 0; ++c) {
    const double tout = stops[c];
    if (c > 0 && !sd.back.empty()) {
      flag = IDASolveB(sd.mem, tout, IDA_NORMAL);
      if (flag < 0) break;
      for (const auto& B : sd.back) {
        realtype tq;
        IDAGetQuadB(sd.mem, B->which, &tq, B->qB);
        const double g = Eigen::Map<Vec>(N_VGetArrayPointer(B->qB), nv).lpNorm<Eigen::Infinity>();
        if (g > 0) IDAQuadSStolerancesB(sd.mem, B->which, im.o.rtol, im.o.atol * g);
      }
    }
    for (size_t b = 0; b < breaks.size(); ++b)
      if (std::abs(breaks[b].t - tout) <= eps)
        if (auto msg = create(b); !msg.empty()) return msg;
  }
  st.adjoint_problems = static_cast<long>(sd.back.size());
  if (sd.back.empty()) return "";
  long v;
  for (const auto& B : sd.back) {
    void* bm = IDAGetAdjIDABmem(sd.mem, B->which);
    IDAGetNumSteps(bm, &v), st.adjoint_steps += v;
    IDAGetNumResEvals(bm, &v), st.adjoint_residual_evaluations += v;
    IDAGetNumJacEvals(bm, &v), st.adjoint_jacobian_evaluations += v;
  }
  if (flag < 0)
    return "IDAS backward integration failed (flag " + std::to_string(flag) + ")" +
           (im.adj_error.empty() ? "" : ": " + im.adj_error);
  for (const auto& B : sd.back) {
    realtype tret;
    if (IDAGetQuadB(sd.mem, B->which, &tret, B->qB)) return "IDAGetQuadB failed";
    size_t b = 0;
    while (breaks[b].t != B->tb) ++b;
    // ∫_{t0}^{t_b} (∂g/∂p − ξᵀF_p) dt; + (ξᵀ F_ẏ y_p)(t0) = 0: q_p(t0) = q̇_p(t0) = 0
    dQ[b].row(B->k) = Eigen::Map<Vec>(N_VGetArrayPointer(B->qB), nv).transpose();
  }
  return "";
}

}  // namespace

IdasGGL::IdasGGL(const Model& model, const ModelParams& params, IdasOptions o)
    : impl_(std::make_unique<Impl>(model, params, o)) {}
IdasGGL::~IdasGGL() = default;
void IdasGGL::set_quadrature(IdasQuadrature* q) { impl_->quad = q; }

IdasStats IdasGGL::run(State s0, const Output& out) { return run_mode(std::move(s0), nullptr, Vec(), out, Mode::kPrimal); }

IdasStats IdasGGL::run_with_sensitivities(State s0, const Parameterization& design, const Vec& pv, const Output& out) {
  return run_mode(std::move(s0), &design, pv, out, design.size() > 0 ? Mode::kForward : Mode::kPrimal);
}

IdasStats IdasGGL::run_adjoint(State s0, const Parameterization& design, const Vec& pv, const Output& out) {
  return run_mode(std::move(s0), &design, pv, out, Mode::kAdjoint);
}

IdasStats IdasGGL::run_mode(State s0, const Parameterization* design, const Vec& pv, const Output& out, Mode mode) {
  auto& im = *impl_;
  const auto t_start = std::chrono::steady_clock::now();
  IdasStats st;
  auto fail = [&](const std::string& msg) {
    st.ok = false;
    st.message = msg;
    st.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    return st;
  };
  if (!(im.o.klu_pivot_tolerance > 0 && im.o.klu_pivot_tolerance <= 1))
    return fail("IdasOptions::klu_pivot_tolerance must be in (0, 1], got " + std::to_string(im.o.klu_pivot_tolerance));
  if (im.o.max_order < 0 || im.o.max_order > 5)
    return fail("IdasOptions::max_order must be 0 (auto) or 1-5, got " + std::to_string(im.o.max_order));
  const Model& m = im.m;
  const int nq = im.nq, nc = im.nc, N = im.N;
  const int nv = design ? design->size() : 0;
  const bool sens = mode == Mode::kForward && nv > 0, adjoint = mode == Mode::kAdjoint;
  if (adjoint && (nv == 0 || !im.quad || im.quad->size() == 0))
    return fail("an adjoint run needs design variables and at least one time-integral response (quadrature)");
  // ---- consistent initial values (index-1 system), scaling
  s0.v.conservativeResize(nq);
  if (s0.lambda.size() != nc) s0.lambda.setZero(nc);
  if (s0.a.size() != nq) s0.a.setZero(nq);
  SparseLU lu;
  lu.analyze(m.pattern());
  if (auto r = project_initial_state(m, im.nominal, s0, lu, 1e-13 * m.length_scale()); !r.ok()) return fail(r.message);
  {
    // ẏ(t0) from the right limit of the drivers' accelerations: a law that switches on at t0
    // (a ramp) has q̈(t0⁺) ≠ q̈(t0⁻), and IDAS fails its first error tests from the left limit
    State right = s0;
    right.t = s0.t + 1e-9 * im.o.h_out;
    if (auto r = consistent_accelerations(m, im.nominal, 1.0, right, lu); !r.ok()) return fail(r.message);
    s0.a = right.a;
    s0.lambda = right.lambda;
  }
  const double kappa = GeneralizedAlpha::automatic_scaling(m, im.nominal, s0, AlphaCoefficients::make(0.8, im.o.h_out));
  im.s3 = kappa;
  im.s1 = im.s4 = kappa * im.o.h_out;
  im.t_start = s0.t;
  Mat dqdd0, dl0;
  if (sens || adjoint) {
    im.design = design;
    im.p_nominal = pv;
    im.p.assign(pv.data(), pv.data() + nv);
    // parameter directions ∂(ModelParams)/∂p_i (F_p, consistent sensitivity initial values)
    ModelParams tmp = im.nominal;
    im.dirs = design->apply_with_directions(pv, tmp);
  }
  if (sens) {
    Mat B(m.n(), nv);
    Vec col;
    for (int i = 0; i < nv; ++i) {
      m.residual_param_derivative(s0, im.nominal, im.dirs[i], col);
      B.col(i) = -col;
    }
    lu.solve(B);  // still holds [M Φ_qᵀ; Φ_q 0] (k = 1) from consistent_accelerations
    dqdd0 = B.topRows(nq);
    dl0 = B.bottomRows(nc);
  }
  // ---- SUNDIALS objects
  Sundials sd;
  if (SUNContext_Create(nullptr, &sd.ctx)) return fail("SUNContext_Create failed");
  sd.y = N_VNew_Serial(N, sd.ctx);
  sd.yp = N_VNew_Serial(N, sd.ctx);
  sd.id = N_VNew_Serial(N, sd.ctx);
  sd.atol = N_VNew_Serial(N, sd.ctx);
  sd.dky = N_VNew_Serial(N, sd.ctx);
  Eigen::Map<Vec> y(N_VGetArrayPointer(sd.y), N), yp(N_VGetArrayPointer(sd.yp), N), id(N_VGetArrayPointer(sd.id), N),
      atol(N_VGetArrayPointer(sd.atol), N);
  y << s0.q, s0.v, s0.lambda, Vec::Zero(nc);
  yp << s0.v, s0.a, Vec::Zero(nc), Vec::Zero(nc);
  id << Vec::Ones(2 * nq), Vec::Zero(2 * nc);
  // A velocity whose DOF carries no mass (a massless link's coordinates, the angle of a point
  // mass on a slider) never appears differentiated: M v̇ has a zero row there, and v is fixed by
  // the velocity constraints (F4). Treated as differential it made the corrector fail (flag -4)
  // on generated mechanisms with massless links at tight tolerances; it is algebraic.
  {
    Mat x(nq, 1), Mx(nq, 1);
    for (int i = 0; i < nq; ++i) x(i, 0) = 1.0 + 0.37 * std::sin(1.0 + i);  // generic: no cancellation
    m.mass_damping_product(s0, im.nominal, x, Mat::Zero(nq, 1), Mx);
    const double scale = Mx.cwiseAbs().maxCoeff();
    for (int i = 0; i < nq; ++i)
      if (std::abs(Mx(i, 0)) <= 1e-14 * scale) id[nq + i] = 0, ++st.massless_velocities;
  }
  const double L = m.length_scale(), T = std::max(im.o.t_end, im.o.h_out);
  const bool positions_only = im.o.error_test == IdasOptions::ErrorTest::kPositions ||
                              (im.o.error_test == IdasOptions::ErrorTest::kAuto && !m.flexible_bodies().empty());
  st.error_test = positions_only ? "positions" : "positions+velocities";
  st.max_order = im.o.max_order > 0 ? im.o.max_order : m.flexible_bodies().empty() ? 5 : 2;
  // velocities out of the error test: an absolute tolerance so large that their weight vanishes
  atol << Vec::Constant(nq, im.o.atol * L), Vec::Constant(nq, positions_only ? 1e30 : im.o.atol * L / T),
      Vec::Constant(2 * nc, 1.0);
  sd.mem = IDACreate(sd.ctx);
  if (!sd.mem) return fail("IDACreate failed");
  if (IDAInit(sd.mem, res_tramp, 0.0 + s0.t, sd.y, sd.yp) || IDASVtolerances(sd.mem, im.o.rtol, sd.atol) ||
      IDASetUserData(sd.mem, &im) || IDASetId(sd.mem, sd.id) || IDASetSuppressAlg(sd.mem, SUNTRUE) ||
      IDASetMaxNumSteps(sd.mem, im.o.max_steps) || IDASetMaxOrd(sd.mem, st.max_order))
    return fail("IDAS set-up failed");
  // Initial step (at t0 and at each restart): where ½h²‖q̈‖ reaches the position tolerance.
  // IDAS's own estimate bounds h‖ẏ‖ by the weights of every component, and velocities that start
  // at rest have only their absolute tolerance, atol·L/t_end: on Andrews' squeezer at rtol ≤ 5e-11
  // that gave h ~ 1e-19 s, where the corrector cannot converge in floating point (flag -4 at t = 0).
  auto set_initial_step = [&](const Vec& q, const Vec& a) -> bool {
    double wa = 0;
    for (int i = 0; i < nq; ++i) {
      const double w = a[i] / (im.o.rtol * std::abs(q[i]) + im.o.atol * L);
      wa += w * w;
    }
    wa = std::sqrt(wa / nq);
    const double h0 = wa > 0 && std::isfinite(wa) ? std::min(0.1 * im.o.h_out, std::sqrt(2.0 / wa)) : 0.0;
    return IDASetInitStep(sd.mem, h0) == IDA_SUCCESS;  // 0: IDAS's own estimate
  };
  if (!set_initial_step(s0.q, s0.a)) return fail("IDAS set-up failed (initial step)");
  const SpMat J0 = im.jacobian(s0.t, 1.0, y.data(), yp.data());
  sd.A = SUNSparseMatrix(N, N, J0.nonZeros(), CSC_MAT, sd.ctx);
  sd.LS = SUNLinSol_KLU(sd.y, sd.A, sd.ctx);
  if (sd.LS) SUNLinSol_KLUGetCommon(sd.LS)->tol = im.o.klu_pivot_tolerance;
  // Adjoint runs: IDASolveB recomputes the forward steps between checkpoints and stores them in
  // a fixed array of adjoint_checkpoint_steps + 1 points (IDAAdataStore, IDAS 6.4), with no bound
  // check: the recomputation must repeat the original steps bit for bit. SUNLinSol_KLU refactors
  // with the pivot sequence of its last full factorization, which depends on the history, so a
  // recomputed interval could take more steps and crash (the full robot arm at rtol 1e-8 did).
  // A fresh analysis and factorization at every Jacobian makes each solve history-free.
  im.fresh_klu = adjoint ? sd.LS : nullptr;
  if (!sd.A || !sd.LS || IDASetLinearSolver(sd.mem, sd.LS, sd.A) || IDASetJacFn(sd.mem, jac_tramp))
    return fail("IDAS linear solver set-up failed");
  std::vector<double> pbar;
  if (sens) {
    const Vec range = design->upper() - design->lower();
    sd.ns = nv;
    sd.yS = N_VCloneVectorArray(nv, sd.y);
    sd.ypS = N_VCloneVectorArray(nv, sd.y);
    sd.dkyS = N_VCloneVectorArray(nv, sd.y);
    for (int i = 0; i < nv; ++i) {
      Eigen::Map<Vec> ys(N_VGetArrayPointer(sd.yS[i]), N), yps(N_VGetArrayPointer(sd.ypS[i]), N);
      ys.setZero();
      yps.setZero();
      ys.segment(2 * nq, nc) = dl0.col(i);
      yps.segment(nq, nq) = dqdd0.col(i);
      pbar.push_back(std::max(std::abs(pv[i]), 1e-2 * range[i]));
    }
    const int ism = im.o.staggered ? IDA_STAGGERED : IDA_SIMULTANEOUS;
    if (IDASensInit(sd.mem, nv, ism, im.o.analytic_sensitivity_residual ? sens_tramp : nullptr, sd.yS, sd.ypS) ||
        IDASensEEtolerances(sd.mem) || IDASetSensErrCon(sd.mem, SUNTRUE) ||
        IDASetSensParams(sd.mem, im.p.data(), pbar.data(), nullptr))
      return fail("IDAS sensitivity set-up failed");
  }
  const int nQ = im.quad ? im.quad->size() : 0;
  if (nQ > 0) {
    sd.yQ = N_VNew_Serial(nQ, sd.ctx);
    N_VConst(0.0, sd.yQ);
    if (IDAQuadInit(sd.mem, quad_tramp, sd.yQ)) return fail("IDAS quadrature set-up failed");
    if (sens) {
      sd.yQS = N_VCloneVectorArray(nv, sd.yQ);
      for (int i = 0; i < nv; ++i) N_VConst(0.0, sd.yQS[i]);
      if (IDAQuadSensInit(sd.mem, im.o.analytic_sensitivity_residual ? quad_sens_tramp : nullptr, sd.yQS))
        return fail("IDAS quadrature sensitivity set-up failed");
    }
  }
  long ncheck = 0;
  if (adjoint && IDAAdjInit(sd.mem, std::max(1L, im.o.adjoint_checkpoint_steps), IDA_HERMITE))
    return fail("IDAS adjoint set-up (IDAAdjInit) failed");
  std::vector<double> breaks;
  if (nQ > 0)
    for (double b : im.quad->breakpoints())
      if (b > s0.t + 1e-12 * im.o.h_out && b < im.o.t_end - 1e-12 * im.o.h_out) breaks.push_back(b);
  std::sort(breaks.begin(), breaks.end());
  breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
  size_t next_break = 0;
  // Forward runs also stop where a driver's acceleration or a load law has a kink, and restart
  // there from consistent right-limit values: a BDF step across one, or a restart from the left
  // limit's history, fails the corrector (flag -4) as the acceleration and λ jump. The adjoint
  // run cannot stop (see below) and steps across them.
  struct Stop {
    double t;
    bool is_break, is_kink;
  };
  std::vector<Stop> stops;
  for (double t : breaks) stops.push_back({t, true, false});
  if (!adjoint) {
    const double margin = 1e-12 * im.o.h_out;
    for (double t : im.m.time_kinks(s0.t + margin, im.o.t_end - margin)) stops.push_back({t, false, true});
    std::stable_sort(stops.begin(), stops.end(), [](const Stop& a, const Stop& b) { return a.t < b.t; });
    std::vector<Stop> merged;  // one stop for near-equal times (a window boundary keeps its time)
    for (const Stop& x : stops) {
      if (!merged.empty() && x.t - merged.back().t <= margin) {
        Stop& m0 = merged.back();
        if (x.is_break && !m0.is_break) m0.t = x.t;
        m0.is_break |= x.is_break, m0.is_kink |= x.is_kink;
        continue;
      }
      merged.push_back(x);
    }
    stops = std::move(merged);
  }
  size_t next_stop = 0;
  if (!stops.empty() && !adjoint) IDASetStopTime(sd.mem, stops[0].t);
  Vec Qv(nQ);
  Mat dQ(nQ, nv);
  std::vector<Breakpoint> at_breaks;  // adjoint runs
  auto report_quadrature = [&](double t) {
    // Q interpolated at t itself: after IDASolveF (adjoint runs) IDAGetQuad returned Q at an
    // earlier return time (0.039 for 0.04 on generated seed 111: values 2 % off)
    IDAGetQuadDky(sd.mem, t, 0, sd.yQ);
    Qv = Eigen::Map<Vec>(N_VGetArrayPointer(sd.yQ), nQ);
    if (adjoint) return at_breaks.push_back({t, Qv, y, yp});
    if (sens) {
      IDAGetQuadSensDky(sd.mem, t, 0, sd.yQS);
      for (int i = 0; i < nv; ++i) dQ.col(i) = Eigen::Map<Vec>(N_VGetArrayPointer(sd.yQS[i]), nQ);
    }
    im.quad->on_breakpoint(t, Qv, sens ? &dQ : nullptr);
  };
  // Restart at a kink t_k: q, v, the sensitivities of q and v and the quadratures are continuous;
  // q̈ and λ are re-solved from the index-1 system at t_k⁺ (as at t0), the sensitivities' rates
  // restart from the left limit (IDAS's order-1 restart corrects them within its error test).
  auto restart_at_kink = [&](double tk) -> std::string {
    State s;
    s.t = tk + 1e-9 * im.o.h_out;
    s.q = y.head(nq), s.v = y.segment(nq, nq), s.lambda = y.segment(2 * nq, nc);
    s.a = yp.segment(nq, nq);
    if (auto r = consistent_accelerations(m, im.nominal, 1.0, s, lu); !r.ok())
      return "IDAS restart at the law kink t = " + std::to_string(tk) + ": " + r.message;
    y.segment(2 * nq, nc) = s.lambda;
    yp.head(nq) = s.v;
    yp.segment(nq, nq) = s.a;
    yp.tail(2 * nc).setZero();
    realtype tr;
    if (sens) {
      IDAGetSens(sd.mem, &tr, sd.yS);
      IDAGetSensDky(sd.mem, tk, 1, sd.ypS);
    }
    if (nQ > 0) {
      IDAGetQuad(sd.mem, &tr, sd.yQ);
      if (sens) IDAGetQuadSens(sd.mem, &tr, sd.yQS);
    }
    if (IDAReInit(sd.mem, tk, sd.y, sd.yp) != IDA_SUCCESS || !set_initial_step(s.q, s.a) ||
        (sens && IDASensReInit(sd.mem, im.o.staggered ? IDA_STAGGERED : IDA_SIMULTANEOUS, sd.yS, sd.ypS) !=
                     IDA_SUCCESS) ||
        (nQ > 0 && IDAQuadReInit(sd.mem, sd.yQ) != IDA_SUCCESS) ||
        (nQ > 0 && sens && IDAQuadSensReInit(sd.mem, sd.yQS) != IDA_SUCCESS))
      return "IDAS could not restart at the law kink t = " + std::to_string(tk);
    return "";
  };
  // ---- outputs on the grid
  Mat dq(nq, nv), dv(nq, nv), da(nq, nv), dl(nc, nv);
  auto emit = [&](double t) {
    State s;
    s.t = t;
    s.q = y.head(nq);
    s.v = y.segment(nq, nq);
    s.lambda = y.segment(2 * nq, nc);
    IDAGetDky(sd.mem, t, 1, sd.dky);
    s.a = Eigen::Map<Vec>(N_VGetArrayPointer(sd.dky), N).segment(nq, nq);
    if (!sens) return out(s, nullptr, nullptr, nullptr, nullptr);
    realtype tr;
    IDAGetSens(sd.mem, &tr, sd.yS);
    IDAGetSensDky(sd.mem, t, 1, sd.dkyS);
    for (int i = 0; i < nv; ++i) {
      const Eigen::Map<Vec> ys(N_VGetArrayPointer(sd.yS[i]), N), dys(N_VGetArrayPointer(sd.dkyS[i]), N);
      dq.col(i) = ys.head(nq);
      dv.col(i) = ys.segment(nq, nq);
      dl.col(i) = ys.segment(2 * nq, nc);
      da.col(i) = dys.segment(nq, nq);
    }
    out(s, &dq, &dv, &da, &dl);
  };
  {  // t0
    State s = s0;
    if (sens) {
      dq.setZero(), dv.setZero(), da = dqdd0, dl = dl0;
      out(s, &dq, &dv, &da, &dl);
    } else {
      out(s, nullptr, nullptr, nullptr, nullptr);
    }
  }
  const long n_out = std::lround(std::ceil((im.o.t_end - s0.t) / im.o.h_out - 1e-9));
  double t_last = s0.t;
  for (long k = 1; k <= n_out; ++k) {
    const double tout = s0.t + k * im.o.h_out;
    realtype tret = 0;
    int flag;
    const double eps = 1e-12 * im.o.h_out;
    if (!adjoint) {
      // window boundaries are stop times (set before IDAS's internal time can pass them): a step
      // ends exactly on each
      while ((flag = IDASolve(sd.mem, tout, &tret, sd.y, sd.yp, IDA_NORMAL)) == IDA_TSTOP_RETURN) {
        if (stops[next_stop].is_break) report_quadrature(tret);
        if (stops[next_stop].is_kink)
          if (auto msg = restart_at_kink(tret); !msg.empty()) {
            flag = -1;
            st.message = msg;
            break;
          }
        if (++next_stop < stops.size()) IDASetStopTime(sd.mem, stops[next_stop].t);
        if (tret >= tout - eps) break;
      }
    } else {
      // no stop times: IDAS (6.4) re-applies the last one to every recomputation between
      // checkpoints in IDASolveB (IDAAdataStore), which fails once it lies behind. The
      // boundaries are extra output times instead (interpolated; the integrands are smooth).
      auto solve_to = [&](double t) {
        int nck = 0;
        const int f = IDASolveF(sd.mem, t, &tret, sd.y, sd.yp, IDA_NORMAL, &nck);
        ncheck = nck;
        return f;
      };
      flag = 0;
      while (flag >= 0 && next_break < breaks.size() && breaks[next_break] < tout - eps)
        if ((flag = solve_to(breaks[next_break])) >= 0) report_quadrature(tret), ++next_break;
      if (flag >= 0) flag = solve_to(tout);
      if (flag >= 0 && next_break < breaks.size() && std::abs(breaks[next_break] - tout) <= eps)
        report_quadrature(tout), ++next_break;
    }
    if (flag < 0) {
      st.ok = false;
      if (st.message.empty())
        st.message = "IDAS failed at t = " + std::to_string(tret) + " (flag " + std::to_string(flag) + ")";
      break;
    }
    emit(tout);
    t_last = tout;
  }
  long v;
  IDAGetNumSteps(sd.mem, &v), st.steps = v;
  IDAGetNumResEvals(sd.mem, &v), st.residual_evaluations = v;
  IDAGetNumJacEvals(sd.mem, &v), st.jacobian_evaluations = v;
  IDAGetNumNonlinSolvIters(sd.mem, &v), st.nonlinear_iterations = v;
  IDAGetNumErrTestFails(sd.mem, &v), st.error_test_failures = v;
  IDAGetNumNonlinSolvConvFails(sd.mem, &v), st.nonlinear_convergence_failures = v;
  if (sens) IDAGetSensNumResEvals(sd.mem, &v), st.sensitivity_residual_evaluations = v;
  if (nQ > 0 && st.ok) report_quadrature(t_last);
  if (adjoint && st.ok) {
    st.checkpoints = ncheck;
    const auto t_back = std::chrono::steady_clock::now();
    std::vector<Mat> dQb;
    const std::string msg =
        backward_pass(sd, im, at_breaks, s0.t, positions_only, st.max_order, J0.nonZeros(), st, dQb);
    st.adjoint_wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_back).count();
    if (!msg.empty()) return fail(msg);
    for (size_t b = 0; b < at_breaks.size(); ++b) im.quad->on_breakpoint(at_breaks[b].t, at_breaks[b].Q, &dQb[b]);
  }
  st.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return st;
}

}  // namespace lsmbs
