#pragma once
// IdasGGL's inside, shared by its forward driver (idas_ggl.cpp: primal and forward-sensitivity
// runs, and the forward pass of an adjoint run) and its adjoint driver (idas_adjoint.cpp: the
// backward problems). Impl is what IDAS's C callbacks reach through their user-data pointer: the
// GGL system at the nominal parameters or at the ones IDAS perturbs for difference quotients,
// the quadratures, and the adjoint's right-hand sides. IdasHandles owns the SUNDIALS objects of
// one run.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "lsmbs/integrators/ggl_system.hpp"
#include "lsmbs/integrators/idas_ggl.hpp"
#include "lsmbs/integrators/sundials_handles.hpp"

namespace lsmbs {

struct IdasGGL::Impl {
  const Model& m;
  const ModelParams& nominal;
  IdasOptions o;
  int nq, nc, N;
  GglSystem ggl;
  // design-variable parameters for IDAS difference quotients
  const Parameterization* design = nullptr;
  Vec p_nominal;
  std::vector<double> p;  // the array IDAS perturbs
  std::map<std::vector<double>, ModelParams> perturbed;
  std::vector<ParamDirection> dirs;
  // quadratures
  IdasQuadrature* quad = nullptr;
  Mat qs_dq, qs_dv, qs_da, qs_dl, qs_dg;
  double t_start = 0;

  Impl(const Model& model, const ModelParams& params, IdasOptions opt)
      : m(model),
        nominal(params),
        o(opt),
        nq(model.nq()),
        nc(model.nc()),
        N(2 * model.nq() + 2 * model.nc()),
        ggl(model) {}

  /// The nominal parameters, or those at the design point IDAS perturbed p to (cached).
  const ModelParams& params();
  State state(double t, const double* y, const double* yp) const { return ggl.state(t, y, yp); }
  /// The same in a state kept by Impl (no allocation once sized): for the callbacks IDAS calls
  /// per step or per iteration; valid until the next call.
  const State& state_ref(double t, const double* y, const double* yp) {
    ggl.state_into(t, y, yp, cb_state);
    return cb_state;
  }
  State cb_state;
  // pointer arrays of IDAS's sensitivity vectors (SensitivityArrays, idas_ggl.cpp)
  std::vector<const double*> ptr_a, ptr_b;
  std::vector<double*> ptr_c;

  // IDAS callbacks of the forward problem (idas_ggl.cpp): 0 success, > 0 recoverable.
  int residual(double t, const double* y, const double* yp, double* F);
  SpMat jacobian(double t, double cj, const double* y, const double* yp);
  int sens_residual(double t, const double* y, const double* yp, std::span<const double* const> yS,
                    std::span<const double* const> ypS, std::span<double* const> rS);
  int quad_rhs(double t, const double* y, const double* yp, double* g);
  int quad_sens_rhs(double t, const double* y, const double* yp, std::span<const double* const> yS,
                    std::span<const double* const> ypS, std::span<double* const> gS);

  // The adjoint problem of quadrature k (idas_adjoint.cpp); −1 when the quadrature has no
  // gradient (adj_error says why).
  Vec adj_gq, adj_gv, adj_dr;
  Eigen::RowVectorXd adj_gp;
  std::vector<double> adj_vals;
  std::string adj_error;  // why a backward callback failed (reported by run_adjoint)
  bool adjoint_integrand(int k, const State& s);
  int adjoint_residual(int k, double t, const double* y, const double* yp, const double* yB,
                       const double* ypB, double* rB);
  int adjoint_quadrature(int k, double t, const double* y, const double* yp, const double* yB,
                         double* qB);
  bool adjoint_final_values(int k, double tb, const Vec& y, const Vec& yp, Vec& xi, Vec& xid,
                            double scale[5]);
};

namespace idas {

// One backward problem of an adjoint run: dQ_k(t_b)/dp. Owns its vectors and linear solver;
// its IDAS memory belongs to the forward one (freed by IDAFree).
struct BackwardProblem {
  IdasGGL::Impl* im = nullptr;
  int k = 0, which = -1;
  double tb = 0;
  sun::Vector yB, ypB, idB, atolB, qB;
  sun::Matrix A;
  sun::LinearSolver LS;
};

// The SUNDIALS objects of one run, freed in the reverse order of the members: the IDAS memory
// first (with the backward problems' memories), the context last.
struct IdasHandles {
  sun::Context ctx;
  sun::Vector y, yp, id, atol, dky, yQ;
  sun::VectorArray yS, ypS, dkyS, yQS;
  sun::Matrix A;
  sun::LinearSolver LS;
  std::vector<std::unique_ptr<BackwardProblem>> back;  // backward problems (adjoint runs)
  sun::IdaMemory mem;
};

// Adjoint runs: Q and the forward state at a breakpoint (or the final time).
struct Breakpoint {
  double t;
  Vec Q, y, yp;
};

// The backward pass of an adjoint run (idas_adjoint.cpp): one backward problem per (quadrature
// k, breakpoint t_b) asked for, all integrated to t0 by one IDASolveB; fills dQ[b] (rows not
// asked for: NaN). Returns an empty string or the reason of a failure.
std::string backward_pass(IdasHandles& sd, IdasGGL::Impl& im, const std::vector<Breakpoint>& breaks,
                          double t0, bool positions_only, int max_order, long nnz, IdasStats& st,
                          std::vector<Mat>& dQ);

}  // namespace idas
}  // namespace lsmbs
