#include "lsmbs/integrators/idas_ggl.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/integrators/generalized_alpha.hpp"
#include "lsmbs/integrators/idas_ggl_impl.hpp"
#include "lsmbs/integrators/initial_state.hpp"
#include "lsmbs/linalg/sparse_lu.hpp"

// The forward driver of IdasGGL: options, the callbacks IDAS calls on the forward problem, and
// run_mode (primal runs, forward sensitivities, and the forward pass of an adjoint run, whose
// backward pass is in idas_adjoint.cpp).

namespace lsmbs {

IdasOptions IdasOptions::reference() {
  IdasOptions o;
  o.rtol = 1e-9;
  o.atol = 1e-9;
  return o;
}

std::string IdasOptions::validate() const {
  if (!(rtol > 0)) return "rtol: expected a positive tolerance";
  if (!(atol > 0)) return "atol: expected a positive tolerance";
  if (!(h_out > 0)) return "h_out: expected a positive output step";
  if (!(t_end > 0)) return "t_end: expected a positive final time";
  if (max_steps < 1) return "max_steps: expected at least 1";
  if (max_order < 0 || max_order > 5) return "max_order: expected 0 (auto) or 1-5";
  if (!(klu_pivot_tolerance > 0 && klu_pivot_tolerance <= 1))
    return "klu_pivot_tolerance: expected a value in (0, 1]";
  if (adjoint_checkpoint_steps < 1) return "adjoint_checkpoint_steps: expected at least 1";
  return {};
}

const ModelParams& IdasGGL::Impl::params() {
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

int IdasGGL::Impl::residual(double t, const double* y, const double* yp, double* F) {
  return ggl.residual(params(), t, y, yp, F)
             ? 0
             : 1;  // 1 recoverable: IDAS retries with a smaller step
}

SpMat IdasGGL::Impl::jacobian(double t, double cj, const double* y, const double* yp) {
  return ggl.jacobian(params(), t, cj, y, yp);
}

// Analytic sensitivity residuals F_y yS + F_ẏ ẏS + F_p (all variables).
int IdasGGL::Impl::sens_residual(double t, const double* y, const double* yp,
                                 std::span<const double* const> yS,
                                 std::span<const double* const> ypS, std::span<double* const> rS) {
  ggl.sensitivity_residual(nominal, t, y, yp, dirs, yS, ypS, rS);
  return 0;
}

int IdasGGL::Impl::quad_rhs(double t, const double* y, const double* yp, double* g) {
  quad->integrand(state_ref(t, y, yp), params(), g);
  return 0;
}

int IdasGGL::Impl::quad_sens_rhs(double t, const double* y, const double* yp,
                                 std::span<const double* const> yS,
                                 std::span<const double* const> ypS, std::span<double* const> gS) {
  const int nv = static_cast<int>(yS.size());
  qs_dq.resize(nq, nv), qs_dv.resize(nq, nv), qs_da.resize(nq, nv), qs_dl.resize(nc, nv);
  for (int i = 0; i < nv; ++i) {
    const Eigen::Map<const Vec> ys(yS[i], N), yps(ypS[i], N);
    qs_dq.col(i) = ys.head(nq);
    qs_dv.col(i) = ys.segment(nq, nq);
    qs_dl.col(i) = ys.segment(2 * nq, nc);
    qs_da.col(i) = yps.segment(nq, nq);
  }
  quad->integrand_sensitivity(state_ref(t, y, yp), nominal, qs_dq, qs_dv, qs_da, qs_dl, qs_dg);
  for (int i = 0; i < nv; ++i) Eigen::Map<Vec>(gS[i], quad->size()) = qs_dg.col(i);
  return 0;
}

namespace {

using sun::map;

int res_tramp(realtype t, N_Vector y, N_Vector yp, N_Vector rr, void* ud) {
  return static_cast<IdasGGL::Impl*>(ud)->residual(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp),
                                                   N_VGetArrayPointer(rr));
}

int jac_tramp(realtype t, realtype cj, N_Vector y, N_Vector yp, N_Vector, SUNMatrix J, void* ud,
              N_Vector, N_Vector, N_Vector) {
  auto* im = static_cast<IdasGGL::Impl*>(ud);
  sun::copy_to(im->jacobian(t, cj, N_VGetArrayPointer(y), N_VGetArrayPointer(yp)), J);
  return 0;
}

// The data of IDAS's arrays of sensitivity vectors (two inputs, one output) as pointer arrays, in
// Impl's buffers (no allocation once sized).
struct SensitivityArrays {
  std::span<const double*const> a, b;
  std::span<double* const> c;
  SensitivityArrays(IdasGGL::Impl& im, int n, const N_Vector* va, const N_Vector* vb,
                    const N_Vector* vc) {
    im.ptr_a.resize(n), im.ptr_b.resize(n), im.ptr_c.resize(n);
    for (int i = 0; i < n; ++i)
      im.ptr_a[i] = N_VGetArrayPointer(va[i]), im.ptr_b[i] = N_VGetArrayPointer(vb[i]),
      im.ptr_c[i] = N_VGetArrayPointer(vc[i]);
    a = im.ptr_a, b = im.ptr_b, c = im.ptr_c;
  }
};

int sens_tramp(int Ns, realtype t, N_Vector y, N_Vector yp, N_Vector, N_Vector* yS, N_Vector* ypS,
               N_Vector* rS, void* ud, N_Vector, N_Vector, N_Vector) {
  auto* im = static_cast<IdasGGL::Impl*>(ud);
  const SensitivityArrays v(*im, Ns, yS, ypS, rS);
  return im->sens_residual(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), v.a, v.b, v.c);
}

int quad_tramp(realtype t, N_Vector y, N_Vector yp, N_Vector rQ, void* ud) {
  return static_cast<IdasGGL::Impl*>(ud)->quad_rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp),
                                                   N_VGetArrayPointer(rQ));
}

int quad_sens_tramp(int Ns, realtype t, N_Vector y, N_Vector yp, N_Vector* yS, N_Vector* ypS,
                    N_Vector, N_Vector* rQS, void* ud, N_Vector, N_Vector, N_Vector) {
  auto* im = static_cast<IdasGGL::Impl*>(ud);
  const SensitivityArrays v(*im, Ns, yS, ypS, rQS);
  return im->quad_sens_rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(yp), v.a, v.b, v.c);
}

}  // namespace

IdasGGL::IdasGGL(const Model& model, const ModelParams& params, IdasOptions o)
    : impl_(std::make_unique<Impl>(model, params, o)) {}
IdasGGL::~IdasGGL() = default;
void IdasGGL::set_quadrature(IdasQuadrature* q) { impl_->quad = q; }

IdasStats IdasGGL::run(State s0, const Output& out) {
  return run_mode(std::move(s0), nullptr, Vec(), out, Mode::kPrimal);
}

IdasStats IdasGGL::run_with_sensitivities(State s0, const Parameterization& design, const Vec& pv,
                                          const Output& out) {
  return run_mode(std::move(s0), &design, pv, out,
                  design.size() > 0 ? Mode::kForward : Mode::kPrimal);
}

IdasStats IdasGGL::run_adjoint(State s0, const Parameterization& design, const Vec& pv,
                               const Output& out) {
  return run_mode(std::move(s0), &design, pv, out, Mode::kAdjoint);
}

IdasStats IdasGGL::run_mode(State s0, const Parameterization* design, const Vec& pv,
                            const Output& out, Mode mode) {
  auto& im = *impl_;
  const auto t_start = std::chrono::steady_clock::now();
  IdasStats st;
  auto fail = [&](const std::string& msg) {
    st.ok = false;
    st.message = msg;
    st.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    return st;
  };
  if (auto msg = im.o.validate(); !msg.empty()) return fail("invalid IDAS option " + msg);
  const Model& m = im.m;
  const int nq = im.nq, nc = im.nc, N = im.N;
  const int nv = design ? design->size() : 0;
  const bool sens = mode == Mode::kForward && nv > 0, adjoint = mode == Mode::kAdjoint;
  if (adjoint && (nv == 0 || !im.quad || im.quad->size() == 0))
    return fail(
        "an adjoint run needs design variables and at least one time-integral response "
        "(quadrature)");
  // ---- consistent initial values (index-1 system), scaling
  s0.v.conservativeResize(nq);
  if (s0.lambda.size() != nc) s0.lambda.setZero(nc);
  if (s0.a.size() != nq) s0.a.setZero(nq);
  SparseLU lu;
  lu.analyze(m.pattern());
  if (auto r = project_initial_state(m, im.nominal, s0, lu, 1e-13 * m.length_scale()); !r.ok())
    return fail(r.message);
  {
    // ẏ(t0) from the right limit of the drivers' accelerations: a law that switches on at t0
    // (a ramp) has q̈(t0⁺) ≠ q̈(t0⁻), and IDAS fails its first error tests from the left limit
    State right = s0;
    right.t = s0.t + 1e-9 * im.o.h_out;
    if (auto r = consistent_accelerations(m, im.nominal, 1.0, right, lu); !r.ok())
      return fail(r.message);
    s0.a = right.a;
    s0.lambda = right.lambda;
  }
  const double kappa = GeneralizedAlpha::automatic_scaling(
      m, im.nominal, s0, AlphaCoefficients::make(0.8, im.o.h_out));
  im.ggl.set_scales({.s1 = kappa * im.o.h_out, .s3 = kappa, .s4 = kappa * im.o.h_out});
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
  idas::IdasHandles sd;
  if (!sd.ctx.create()) return fail("SUNContext_Create failed");
  sd.y = sun::new_vector(N, sd.ctx);
  sd.yp = sun::new_vector(N, sd.ctx);
  sd.id = sun::new_vector(N, sd.ctx);
  sd.atol = sun::new_vector(N, sd.ctx);
  sd.dky = sun::new_vector(N, sd.ctx);
  Eigen::Map<Vec> y = map(sd.y.get()), yp = map(sd.yp.get()), id = map(sd.id.get()),
                  atol = map(sd.atol.get());
  y << s0.q, s0.v, s0.lambda, Vec::Zero(nc);
  yp << s0.v, s0.a, Vec::Zero(nc), Vec::Zero(nc);
  id << Vec::Ones(2 * nq), Vec::Zero(2 * nc);
  // A velocity whose DOF carries no mass (a massless link's coordinates, the angle of a point
  // mass on a slider) never appears differentiated: M v̇ has a zero row there, and v is fixed by
  // the velocity constraints (F4). Treated as differential it made the corrector fail (flag -4)
  // on generated mechanisms with massless links at tight tolerances; it is algebraic.
  {
    Mat x(nq, 1), Mx(nq, 1);
    for (int i = 0; i < nq; ++i)
      x(i, 0) = 1.0 + 0.37 * std::sin(1.0 + i);  // generic: no cancellation
    m.mass_damping_product(s0, im.nominal, x, Mat::Zero(nq, 1), Mx);
    const double scale = Mx.cwiseAbs().maxCoeff();
    for (int i = 0; i < nq; ++i)
      if (std::abs(Mx(i, 0)) <= 1e-14 * scale) id[nq + i] = 0, ++st.massless_velocities;
  }
  const double L = m.length_scale(), T = std::max(im.o.t_end, im.o.h_out);
  const bool positions_only =
      im.o.error_test == IdasOptions::ErrorTest::kPositions ||
      (im.o.error_test == IdasOptions::ErrorTest::kAuto && !m.flexible_bodies().empty());
  st.error_test = positions_only ? "positions" : "positions+velocities";
  st.max_order = im.o.max_order > 0 ? im.o.max_order : m.flexible_bodies().empty() ? 5 : 2;
  // velocities out of the error test: an absolute tolerance so large that their weight vanishes
  atol << Vec::Constant(nq, im.o.atol * L),
      Vec::Constant(nq, positions_only ? 1e30 : im.o.atol * L / T), Vec::Constant(2 * nc, 1.0);
  if (!sd.mem.create(sd.ctx)) return fail("IDACreate failed");
  void* const mem = sd.mem.get();
  if (IDAInit(mem, res_tramp, 0.0 + s0.t, sd.y.get(), sd.yp.get()) ||
      IDASVtolerances(mem, im.o.rtol, sd.atol.get()) || IDASetUserData(mem, &im) ||
      IDASetId(mem, sd.id.get()) || IDASetSuppressAlg(mem, SUNTRUE) ||
      IDASetMaxNumSteps(mem, im.o.max_steps) || IDASetMaxOrd(mem, st.max_order))
    return fail("IDAS set-up failed");
  // Initial step (at t0 and at each restart): where ½h²‖q̈‖ reaches the position tolerance.
  // IDAS's own estimate bounds h‖ẏ‖ by the weights of every component, and velocities that start
  // at rest have only their absolute tolerance, atol·L/t_end: on Andrews' squeezer at rtol ≤ 5e-11
  // that gave h ~ 1e-19 s, where the corrector cannot converge in floating point (flag -4 at t =
  // 0).
  auto set_initial_step = [&](const Vec& q, const Vec& a) -> bool {
    double wa = 0;
    for (int i = 0; i < nq; ++i) {
      const double w = a[i] / (im.o.rtol * std::abs(q[i]) + im.o.atol * L);
      wa += w * w;
    }
    wa = std::sqrt(wa / nq);
    const double h0 =
        wa > 0 && std::isfinite(wa) ? std::min(0.1 * im.o.h_out, std::sqrt(2.0 / wa)) : 0.0;
    return IDASetInitStep(mem, h0) == IDA_SUCCESS;  // 0: IDAS's own estimate
  };
  if (!set_initial_step(s0.q, s0.a)) return fail("IDAS set-up failed (initial step)");
  const SpMat J0 = im.jacobian(s0.t, 1.0, y.data(), yp.data());
  sd.A.reset(SUNSparseMatrix(N, N, J0.nonZeros(), CSC_MAT, sd.ctx.get()));
  // Adjoint runs: IDASolveB recomputes the forward steps between checkpoints and stores them in
  // a fixed array of adjoint_checkpoint_steps + 1 points (IDAAdataStore, IDAS 6.4), with no bound
  // check: the recomputation must repeat the original steps bit for bit. A refactorization uses
  // the pivot sequence of the last full factorization, which depends on the history, so a
  // recomputed interval could take more steps and crash (the full robot arm at rtol 1e-8 did).
  // A factorization with fresh pivoting at every Jacobian makes each solve history-free.
  sd.LS = sun::new_sparse_lu_solver(sd.ctx, im.o.klu_pivot_tolerance, /*fresh_each_setup=*/adjoint);
  if (!sd.A || !sd.LS || IDASetLinearSolver(mem, sd.LS.get(), sd.A.get()) ||
      IDASetJacFn(mem, jac_tramp))
    return fail("IDAS linear solver set-up failed");
  std::vector<double> pbar;
  if (sens) {
    const Vec range = design->upper() - design->lower();
    sd.yS = sun::VectorArray(nv, sd.y.get());
    sd.ypS = sun::VectorArray(nv, sd.y.get());
    sd.dkyS = sun::VectorArray(nv, sd.y.get());
    for (int i = 0; i < nv; ++i) {
      Eigen::Map<Vec> ys = map(sd.yS[i]), yps = map(sd.ypS[i]);
      ys.setZero();
      yps.setZero();
      ys.segment(2 * nq, nc) = dl0.col(i);
      yps.segment(nq, nq) = dqdd0.col(i);
      pbar.push_back(std::max(std::abs(pv[i]), 1e-2 * range[i]));
    }
    const int ism = im.o.staggered ? IDA_STAGGERED : IDA_SIMULTANEOUS;
    if (IDASensInit(mem, nv, ism, im.o.analytic_sensitivity_residual ? sens_tramp : nullptr,
                    sd.yS.get(), sd.ypS.get()) ||
        IDASensEEtolerances(mem) || IDASetSensErrCon(mem, SUNTRUE) ||
        IDASetSensParams(mem, im.p.data(), pbar.data(), nullptr))
      return fail("IDAS sensitivity set-up failed");
  }
  const int nQ = im.quad ? im.quad->size() : 0;
  if (nQ > 0) {
    sd.yQ = sun::new_vector(nQ, sd.ctx);
    N_VConst(0.0, sd.yQ.get());
    if (IDAQuadInit(mem, quad_tramp, sd.yQ.get())) return fail("IDAS quadrature set-up failed");
    if (sens) {
      sd.yQS = sun::VectorArray(nv, sd.yQ.get());
      for (int i = 0; i < nv; ++i) N_VConst(0.0, sd.yQS[i]);
      if (IDAQuadSensInit(mem, im.o.analytic_sensitivity_residual ? quad_sens_tramp : nullptr,
                          sd.yQS.get()))
        return fail("IDAS quadrature sensitivity set-up failed");
    }
  }
  long ncheck = 0;
  if (adjoint && IDAAdjInit(mem, std::max(1L, im.o.adjoint_checkpoint_steps), IDA_HERMITE))
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
    for (double t : im.m.time_kinks(s0.t + margin, im.o.t_end - margin))
      stops.push_back({t, false, true});
    std::stable_sort(stops.begin(), stops.end(),
                     [](const Stop& a, const Stop& b) { return a.t < b.t; });
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
  if (!stops.empty() && !adjoint) IDASetStopTime(mem, stops[0].t);
  Vec Qv(nQ);
  Mat dQ(nQ, nv);
  std::vector<idas::Breakpoint> at_breaks;  // adjoint runs
  auto report_quadrature = [&](double t) {
    // Q interpolated at t itself: after IDASolveF (adjoint runs) IDAGetQuad returned Q at an
    // earlier return time than the one asked for
    IDAGetQuadDky(mem, t, 0, sd.yQ.get());
    Qv = map(sd.yQ.get());
    if (adjoint) return at_breaks.push_back({t, Qv, y, yp});
    if (sens) {
      IDAGetQuadSensDky(mem, t, 0, sd.yQS.get());
      for (int i = 0; i < nv; ++i) dQ.col(i) = map(sd.yQS[i]);
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
      IDAGetSens(mem, &tr, sd.yS.get());
      IDAGetSensDky(mem, tk, 1, sd.ypS.get());
    }
    if (nQ > 0) {
      IDAGetQuad(mem, &tr, sd.yQ.get());
      if (sens) IDAGetQuadSens(mem, &tr, sd.yQS.get());
    }
    if (IDAReInit(mem, tk, sd.y.get(), sd.yp.get()) != IDA_SUCCESS || !set_initial_step(s.q, s.a) ||
        (sens && IDASensReInit(mem, im.o.staggered ? IDA_STAGGERED : IDA_SIMULTANEOUS, sd.yS.get(),
                               sd.ypS.get()) != IDA_SUCCESS) ||
        (nQ > 0 && IDAQuadReInit(mem, sd.yQ.get()) != IDA_SUCCESS) ||
        (nQ > 0 && sens && IDAQuadSensReInit(mem, sd.yQS.get()) != IDA_SUCCESS))
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
    IDAGetDky(mem, t, 1, sd.dky.get());
    s.a = map(sd.dky.get()).segment(nq, nq);
    if (!sens) return out(s, nullptr, nullptr, nullptr, nullptr);
    realtype tr;
    IDAGetSens(mem, &tr, sd.yS.get());
    IDAGetSensDky(mem, t, 1, sd.dkyS.get());
    for (int i = 0; i < nv; ++i) {
      const Eigen::Map<Vec> ys = map(sd.yS[i]), dys = map(sd.dkyS[i]);
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
      while ((flag = IDASolve(mem, tout, &tret, sd.y.get(), sd.yp.get(), IDA_NORMAL)) ==
             IDA_TSTOP_RETURN) {
        if (stops[next_stop].is_break) report_quadrature(tret);
        if (stops[next_stop].is_kink)
          if (auto msg = restart_at_kink(tret); !msg.empty()) {
            flag = -1;
            st.message = msg;
            break;
          }
        if (++next_stop < stops.size()) IDASetStopTime(mem, stops[next_stop].t);
        if (tret >= tout - eps) break;
      }
    } else {
      // no stop times: IDAS (6.4) re-applies the last one to every recomputation between
      // checkpoints in IDASolveB (IDAAdataStore), which fails once it lies behind. The
      // boundaries are extra output times instead (interpolated; the integrands are smooth).
      auto solve_to = [&](double t) {
        int nck = 0;
        const int f = IDASolveF(mem, t, &tret, sd.y.get(), sd.yp.get(), IDA_NORMAL, &nck);
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
        st.message =
            "IDAS failed at t = " + std::to_string(tret) + " (flag " + std::to_string(flag) + ")";
      break;
    }
    // a reflected element is stress-free: a spurious state, not the structure's (docs/methods.md
    // "Inverted elements"); IDAS's error control makes it rare, and it is never reported
    if (const auto inv = m.most_compressed_element(y.head(nq), im.nominal); inv.inverted()) {
      st.ok = false;
      st.message = "IDAS reached a state with an inverted element at t = " + std::to_string(tout) +
                   ": " + inv.describe();
      break;
    }
    emit(tout);
    t_last = tout;
    if (interrupted()) {  // SIGINT/SIGTERM (core/interrupt.hpp): stop at this output time
      st.ok = false;
      st.message = "interrupted (signal " + std::to_string(interrupted()) +
                   ") at t = " + std::to_string(tout) + " s";
      break;
    }
  }
  long v;
  IDAGetNumSteps(mem, &v), st.steps = v;
  IDAGetNumResEvals(mem, &v), st.residual_evaluations = v;
  IDAGetNumJacEvals(mem, &v), st.jacobian_evaluations = v;
  IDAGetNumNonlinSolvIters(mem, &v), st.nonlinear_iterations = v;
  IDAGetNumErrTestFails(mem, &v), st.error_test_failures = v;
  IDAGetNumNonlinSolvConvFails(mem, &v), st.nonlinear_convergence_failures = v;
  if (sens) IDAGetSensNumResEvals(mem, &v), st.sensitivity_residual_evaluations = v;
  if (nQ > 0 && st.ok) report_quadrature(t_last);
  if (adjoint && st.ok) {
    st.checkpoints = ncheck;
    const auto t_back = std::chrono::steady_clock::now();
    std::vector<Mat> dQb;
    const std::string msg = idas::backward_pass(sd, im, at_breaks, s0.t, positions_only,
                                                st.max_order, J0.nonZeros(), st, dQb);
    st.adjoint_wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_back).count();
    if (!msg.empty()) return fail(msg);
    for (size_t b = 0; b < at_breaks.size(); ++b)
      im.quad->on_breakpoint(at_breaks[b].t, at_breaks[b].Q, &dQb[b]);
  }
  st.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return st;
}

RunStatus IdasStats::status() const { return ok ? RunStatus::kComplete : RunStatus::kFailed; }

std::string IdasStats::report() const {
  char b[320];
  std::snprintf(b, sizeof b,
                "IDAS: %s: %ld steps, %ld residual evaluations, %ld Jacobian evaluations, %ld "
                "nonlinear iterations, "
                "%ld error-test failures, %.3f s",
                run_status_name(status()), steps, residual_evaluations, jacobian_evaluations,
                nonlinear_iterations, error_test_failures, wall_seconds);
  std::string r = b;
  if (adjoint_problems > 0) {
    std::snprintf(b, sizeof b, "; adjoint: %ld backward problems, %ld steps, %ld checkpoints",
                  adjoint_problems, adjoint_steps, checkpoints);
    r += b;
  }
  return message.empty() ? r : r + "\n  " + message;
}

}  // namespace lsmbs
