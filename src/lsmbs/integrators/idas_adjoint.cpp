#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/integrators/idas_ggl_impl.hpp"

// The adjoint driver of IdasGGL (run_adjoint): the right-hand sides of the adjoint GGL system
// of a quadrature Q_k (GglSystem::adjoint_residual), its consistent final values, and the
// backward pass over the backward problems after the forward pass (idas_ggl.cpp).

namespace lsmbs {

bool IdasGGL::Impl::adjoint_integrand(int k, const State& s) {
  return quad->integrand_gradient(k, s, nominal, adj_gq, adj_gv, adj_gp, adj_error);
}

int IdasGGL::Impl::adjoint_residual(int k, double t, const double* y, const double* yp,
                                    const double* yB, const double* ypB, double* rB) {
  if (!adjoint_integrand(k, state_ref(t, y, yp))) return -1;
  return ggl.adjoint_residual(nominal, t, y, yp, yB, ypB, adj_gq, adj_gv, rB) ? 0 : 1;
}

// rhsQB = ξᵀ F_p − ∂g/∂p: integrated from t_b back to t0 it gives ∫_{t0}^{t_b} (∂g/∂p − ξᵀF_p) dt.
int IdasGGL::Impl::adjoint_quadrature(int k, double t, const double* y, const double* yp,
                                      const double* yB, double* qB) {
  const State& s = state_ref(t, y, yp);
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
bool IdasGGL::Impl::adjoint_final_values(int k, double tb, const Vec& y, const Vec& yp, Vec& xi,
                                         Vec& xid, double scale[5]) {
  const State s = state(tb, y.data(), yp.data());
  if (!adjoint_integrand(k, s)) return false;
  m.iteration_matrix(s, nominal, Coefficients{1, 0, 0}, 1.0, 0.0, adj_vals);
  const SpMat SM = m.assembler().to_sparse(adj_vals);
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
    adj_error =
        "singular constraint system for the adjoint final values at t = " + std::to_string(tb);
    return false;
  }
  Vec rhs = Vec::Zero(nq + nc);
  rhs.head(nq) = -adj_gv;
  const double s1 = ggl.scales().s1, s3 = ggl.scales().s3, s4 = ggl.scales().s4;
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
  double sq = xid.head(nq).lpNorm<Eigen::Infinity>() * W,
         sv = xid.segment(nq, nq).lpNorm<Eigen::Infinity>() * W;
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

namespace idas {
namespace {

using sun::map;

int res_b_tramp(realtype t, N_Vector y, N_Vector yp, N_Vector yB, N_Vector ypB, N_Vector rB,
                void* ud) {
  auto* b = static_cast<BackwardProblem*>(ud);
  return b->im->adjoint_residual(b->k, t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp),
                                 N_VGetArrayPointer(yB), N_VGetArrayPointer(ypB),
                                 N_VGetArrayPointer(rB));
}

// ∂resB/∂ξ + c_jB ∂resB/∂ξ̇ = −(F_y − c_jB F_ẏ)ᵀ: the forward Jacobian at c_j = −c_jB, transposed
// and negated (Ṁ, the derivative of Ṁ ξ_v, is left out: O(|q̇|) against c_jB M).
int jac_b_tramp(realtype t, realtype cjB, N_Vector y, N_Vector yp, N_Vector, N_Vector, N_Vector,
                SUNMatrix J, void* ud, N_Vector, N_Vector, N_Vector) {
  auto* b = static_cast<BackwardProblem*>(ud);
  const SpMat A = b->im->jacobian(t, -cjB, N_VGetArrayPointer(y), N_VGetArrayPointer(yp));
  SpMat At = -SpMat(A.transpose());
  At.makeCompressed();
  sun::copy_to(At, J);
  return 0;
}

int quad_b_tramp(realtype t, N_Vector y, N_Vector yp, N_Vector yB, N_Vector, N_Vector qB,
                 void* ud) {
  auto* b = static_cast<BackwardProblem*>(ud);
  return b->im->adjoint_quadrature(b->k, t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp),
                                   N_VGetArrayPointer(yB), N_VGetArrayPointer(qB));
}

}  // namespace

std::string backward_pass(IdasHandles& sd, IdasGGL::Impl& im, const std::vector<Breakpoint>& breaks,
                          double t0, bool positions_only, int max_order, long nnz, IdasStats& st,
                          std::vector<Mat>& dQ) {
  const int nq = im.nq, nc = im.nc, N = im.N, nQ = im.quad->size(),
            nv = static_cast<int>(im.dirs.size());
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
      auto bp = std::make_unique<BackwardProblem>();
      BackwardProblem& B = *bp;
      sd.back.push_back(std::move(bp));
      B.im = &im, B.k = k, B.tb = tb;
      B.yB = sun::new_vector(N, sd.ctx);
      B.ypB = sun::new_vector(N, sd.ctx);
      B.idB = sun::new_vector(N, sd.ctx);
      B.atolB = sun::new_vector(N, sd.ctx);
      B.qB = sun::new_vector(nv, sd.ctx);
      map(B.yB.get()) = xi;
      map(B.ypB.get()) = xid;
      map(B.idB.get()) << Vec::Ones(2 * nq), Vec::Zero(2 * nc);
      // Error test: ξ_v (position-like) always; ξ_q (velocity-like: s₁ ξ̇_q = K_tᵀ ξ_v …,
      // M ξ̇_v = −s₁ ξ_q …) only when the forward test has velocities (rigid models); the gradient
      // quadratures too. The adjoint load ∂g/∂q switches on at t_b like a step load and excites
      // every undamped structural mode of ξ_v at the amplitude of its static response, which
      // costs many backward steps on flexible models. ξ_v stays in the test nevertheless: the
      // quadratures' local error estimate does not see the accumulated error of ξ_v, and without
      // it the gradients drift (docs/methods.md, "Adjoint sensitivities").
      const double off = 1e30;  // weight ≈ 0: out of the error test
      map(B.atolB.get()) << Vec::Constant(nq, positions_only ? off : im.o.atol * scale[0]),
          Vec::Constant(nq, im.o.atol * scale[1]), Vec::Constant(nc, im.o.atol * scale[2]),
          Vec::Constant(nc, im.o.atol * scale[3]);
      N_VConst(0.0, B.qB.get());
      void* mem = sd.mem.get();
      if (IDACreateB(mem, &B.which) ||
          IDAInitB(mem, B.which, res_b_tramp, tb, B.yB.get(), B.ypB.get()) ||
          IDASVtolerancesB(mem, B.which, im.o.rtol, B.atolB.get()) ||
          IDASetUserDataB(mem, B.which, &B) || IDASetIdB(mem, B.which, B.idB.get()) ||
          IDASetSuppressAlgB(mem, B.which, SUNTRUE) || IDASetMaxOrdB(mem, B.which, max_order) ||
          IDASetMaxNumStepsB(mem, B.which, im.o.max_steps))
        return "IDAS backward problem set-up failed";
      B.A.reset(SUNSparseMatrix(N, N, nnz, CSC_MAT, sd.ctx.get()));
      B.LS = sun::new_sparse_lu_solver(sd.ctx, im.o.klu_pivot_tolerance, false);
      if (!B.LS || IDASetLinearSolverB(mem, B.which, B.LS.get(), B.A.get()) ||
          IDASetJacFnB(mem, B.which, jac_b_tramp) ||
          IDAQuadInitB(mem, B.which, quad_b_tramp, B.qB.get()))
        return "IDAS backward linear solver or quadrature set-up failed";
      // the gradient quadratures are in the error test (absolute part: atol × gradient scale)
      if (IDAQuadSStolerancesB(mem, B.which, im.o.rtol, im.o.atol * scale[4]) ||
          IDASetQuadErrConB(mem, B.which, SUNTRUE))
        return "IDAS backward quadrature tolerances rejected";
    }
    return "";
  };
  // Backward in chunks (64 over the span, plus every breakpoint). The a-priori gradient scale
  // (scale[4]) can be orders of magnitude too large; after each chunk the absolute tolerance of
  // each gradient quadrature becomes atol × the largest |dQ/dp| accumulated so far
  // (docs/methods.md, "Adjoint sensitivities"). A breakpoint's problems are created when the pass
  // reaches it: IDASolveB requires every existing backward problem to lie ahead of tBout.
  double t_hi = t0;
  for (const auto& bp : breaks) t_hi = std::max(t_hi, bp.t);
  constexpr int kChunks = 64;
  std::vector<double> stops;
  for (int c = 0; c <= kChunks; ++c)
    stops.push_back(c == kChunks ? t0 : t_hi - (t_hi - t0) * c / kChunks);
  for (const auto& bp : breaks) stops.push_back(bp.t);
  std::sort(stops.begin(), stops.end(), std::greater<>());
  const double eps = 1e-12 * std::max(1.0, std::abs(t_hi));
  stops.erase(std::unique(stops.begin(), stops.end(),
                          [&](double a, double b) { return std::abs(a - b) <= eps; }),
              stops.end());
  im.adj_error.clear();
  int flag = 0;
  for (size_t c = 0; c < stops.size() && flag >= 0; ++c) {
    const double tout = stops[c];
    if (interrupted())  // SIGINT/SIGTERM (core/interrupt.hpp): stop between two chunks
      return "interrupted (signal " + std::to_string(interrupted()) +
             ") in the backward pass at t = " + std::to_string(tout) + " s";
    if (c > 0 && !sd.back.empty()) {
      flag = IDASolveB(sd.mem.get(), tout, IDA_NORMAL);
      if (flag < 0) break;
      for (const auto& B : sd.back) {
        realtype tq;
        IDAGetQuadB(sd.mem.get(), B->which, &tq, B->qB.get());
        const double g = map(B->qB.get()).lpNorm<Eigen::Infinity>();
        if (g > 0) IDAQuadSStolerancesB(sd.mem.get(), B->which, im.o.rtol, im.o.atol * g);
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
    void* bm = IDAGetAdjIDABmem(sd.mem.get(), B->which);
    IDAGetNumSteps(bm, &v), st.adjoint_steps += v;
    IDAGetNumResEvals(bm, &v), st.adjoint_residual_evaluations += v;
    IDAGetNumJacEvals(bm, &v), st.adjoint_jacobian_evaluations += v;
  }
  if (flag < 0)
    return "IDAS backward integration failed (flag " + std::to_string(flag) + ")" +
           (im.adj_error.empty() ? "" : ": " + im.adj_error);
  for (const auto& B : sd.back) {
    realtype tret;
    if (IDAGetQuadB(sd.mem.get(), B->which, &tret, B->qB.get())) return "IDAGetQuadB failed";
    size_t b = 0;
    while (breaks[b].t != B->tb) ++b;
    // ∫_{t0}^{t_b} (∂g/∂p − ξᵀF_p) dt; + (ξᵀ F_ẏ y_p)(t0) = 0: q_p(t0) = q̇_p(t0) = 0
    dQ[b].row(B->k) = map(B->qB.get()).transpose();
  }
  return "";
}

}  // namespace idas
}  // namespace lsmbs
