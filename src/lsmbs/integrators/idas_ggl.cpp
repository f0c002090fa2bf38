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
          {"sensitivity_residual", analytic_sensitivity_residual ? "analytic" : "idas_difference_quotients"}};
}

nlohmann::json IdasStats::to_json() const {
  return {{"ok", ok}, {"message", message}, {"steps", steps}, {"residual_evaluations", residual_evaluations},
          {"jacobian_evaluations", jacobian_evaluations}, {"nonlinear_iterations", nonlinear_iterations},
          {"error_test_failures", error_test_failures}, {"nonlinear_convergence_failures", nonlinear_convergence_failures},
          {"sensitivity_residual_evaluations", sensitivity_residual_evaluations}, {"wall_seconds", wall_seconds},
          {"error_test", error_test}, {"max_order", max_order}};
}

struct IdasGGL::Impl {
  const Model& m;
  const ModelParams& nominal;
  IdasOptions o;
  int nq, nc, N;
  double s1 = 1, s3 = 1, s4 = 1;
  // design-variable parameters for IDAS difference quotients
  const Design* design = nullptr;
  Vec p_nominal;
  std::vector<double> p;  // the array IDAS perturbs
  std::map<std::vector<double>, ModelParams> perturbed;
  std::vector<ParamDirection> dirs;
  ModelParams scratch;
  // workspace
  Vec R, phi_t, gamma;
  std::vector<double> vals;
  // quadratures
  IdasQuadrature* quad = nullptr;
  Mat qs_dq, qs_dv, qs_da, qs_dl, qs_dg;

  Impl(const Model& model, const ModelParams& params, IdasOptions opt)
      : m(model), nominal(params), o(opt), nq(model.nq()), nc(model.nc()), N(2 * model.nq() + 2 * model.nc()),
        scratch(params) {}

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
      m.residual_param_derivative(s, nominal, dirs[i], scratch, dr);
      out.segment(nq, nq) += dr.head(nq);
    }
    return 0;
  }
};

namespace {

int res_tramp(realtype t, N_Vector y, N_Vector yp, N_Vector rr, void* ud) {
  return static_cast<IdasGGL::Impl*>(ud)->residual(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), N_VGetArrayPointer(rr));
}

int jac_tramp(realtype t, realtype cj, N_Vector y, N_Vector yp, N_Vector, SUNMatrix J, void* ud, N_Vector, N_Vector,
              N_Vector) {
  auto* im = static_cast<IdasGGL::Impl*>(ud);
  const SpMat A = im->jacobian(t, cj, N_VGetArrayPointer(y), N_VGetArrayPointer(yp));
  if (SM_NNZ_S(J) < A.nonZeros()) SUNSparseMatrix_Reallocate(J, A.nonZeros());
  sunindextype* cp = SM_INDEXPTRS_S(J);
  sunindextype* ri = SM_INDEXVALS_S(J);
  realtype* d = SM_DATA_S(J);
  for (int c = 0; c <= A.cols(); ++c) cp[c] = A.outerIndexPtr()[c];
  for (Eigen::Index k = 0; k < A.nonZeros(); ++k) ri[k] = A.innerIndexPtr()[k], d[k] = A.valuePtr()[k];
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
  ~Sundials() {
    if (mem) IDAFree(&mem);
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

}  // namespace

IdasGGL::IdasGGL(const Model& model, const ModelParams& params, IdasOptions o)
    : impl_(std::make_unique<Impl>(model, params, o)) {}
IdasGGL::~IdasGGL() = default;
void IdasGGL::set_quadrature(IdasQuadrature* q) { impl_->quad = q; }

IdasStats IdasGGL::run(State s0, const Output& out) { return run_with_sensitivities(std::move(s0), Design{}, Vec(), out); }

IdasStats IdasGGL::run_with_sensitivities(State s0, const Design& design, const Vec& pv, const Output& out) {
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
  const int nv = design.size();
  const bool sens = nv > 0;
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
  Mat dqdd0, dl0;
  if (sens) {
    im.design = &design;
    im.p_nominal = pv;
    im.p.assign(pv.data(), pv.data() + nv);
    // parameter directions ∂(ModelParams)/∂p_i for the consistent sensitivity initial values
    ModelParams tmp = im.nominal;
    im.dirs = design.apply_with_directions(pv, tmp);
    Mat B(m.n(), nv);
    Vec col;
    for (int i = 0; i < nv; ++i) {
      m.residual_param_derivative(s0, im.nominal, im.dirs[i], im.scratch, col);
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
  const SpMat J0 = im.jacobian(s0.t, 1.0, y.data(), yp.data());
  sd.A = SUNSparseMatrix(N, N, J0.nonZeros(), CSC_MAT, sd.ctx);
  sd.LS = SUNLinSol_KLU(sd.y, sd.A, sd.ctx);
  if (sd.LS) SUNLinSol_KLUGetCommon(sd.LS)->tol = im.o.klu_pivot_tolerance;
  if (!sd.A || !sd.LS || IDASetLinearSolver(sd.mem, sd.LS, sd.A) || IDASetJacFn(sd.mem, jac_tramp))
    return fail("IDAS linear solver set-up failed");
  std::vector<double> pbar;
  if (sens) {
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
      pbar.push_back(std::max(std::abs(pv[i]), 1e-2 * (design.variables[i].upper - design.variables[i].lower)));
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
  std::vector<double> breaks;
  if (nQ > 0)
    for (double b : im.quad->breakpoints())
      if (b > s0.t + 1e-12 * im.o.h_out && b < im.o.t_end - 1e-12 * im.o.h_out) breaks.push_back(b);
  std::sort(breaks.begin(), breaks.end());
  breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
  size_t next_break = 0;
  if (!breaks.empty()) IDASetStopTime(sd.mem, breaks[0]);
  Vec Qv(nQ);
  Mat dQ(nQ, nv);
  auto report_quadrature = [&](double t) {
    realtype tq;
    IDAGetQuad(sd.mem, &tq, sd.yQ);
    Qv = Eigen::Map<Vec>(N_VGetArrayPointer(sd.yQ), nQ);
    if (sens) {
      IDAGetQuadSens(sd.mem, &tq, sd.yQS);
      for (int i = 0; i < nv; ++i) dQ.col(i) = Eigen::Map<Vec>(N_VGetArrayPointer(sd.yQS[i]), nQ);
    }
    im.quad->on_breakpoint(t, Qv, sens ? &dQ : nullptr);
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
    // window boundaries are stop times (set before IDAS's internal time can pass them): no step
    // straddles the switch of an integrand
    while ((flag = IDASolve(sd.mem, tout, &tret, sd.y, sd.yp, IDA_NORMAL)) == IDA_TSTOP_RETURN) {
      report_quadrature(tret);
      if (++next_break < breaks.size()) IDASetStopTime(sd.mem, breaks[next_break]);
      if (tret >= tout - 1e-12 * im.o.h_out) break;
    }
    if (flag < 0) {
      st.ok = false;
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
  st.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return st;
}

}  // namespace lsmbs
