// The linear solve of one Newton iteration on a 3D solid block, by the direct LUs behind SparseLU
// (KLU, UMFPACK) and by an AMG-preconditioned conjugate gradient (hypre's BoomerAMG, from Debian's
// libhypre-dev), on the same matrix: the integrator's iteration matrix S_t (eq. 13) of the case at
// its initial state, restricted to the unknowns no constraint touches (the clamped nodes and the
// multipliers removed: the symmetric positive definite block an AMG applies to). The LU's solution
// is the reference of the iterative one. docs/performance.md, "Linear solvers on 3D meshes".
//
//   cmake -S . -B build -DLSMBS_BUILD_BENCH=ON && cmake --build build --target lsmbs_amg_block
//   build/bench/lsmbs_amg_block CASE.json --solver amg|umfpack|klu [--rtol 1e-10]
//
// Prints one JSON line: unknowns, nonzeros, the factorization (setup) and solve times, PCG
// iterations, the relative difference from an LU solution (amg), and the peak memory.
#include <HYPRE.h>
#include <HYPRE_krylov.h>
#include <HYPRE_parcsr_ls.h>
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lsmbs/core/clock.hpp"
#include "lsmbs/integrators/generalized_alpha.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/linalg/boomer_amg.hpp"
#include "lsmbs/linalg/sparse_lu.hpp"

using namespace lsmbs;

namespace {

// The free block in compressed columns (its own pattern and values).
struct Block {
  CscPattern pattern;
  std::vector<double> values;
};

// S_t restricted to the generalized coordinates that no constraint row touches.
Block free_block(const CscPattern& P, const std::vector<double>& v, int nq) {
  std::vector<char> held(nq, 0);
  for (int j = 0; j < nq; ++j)
    for (int p = P.col_ptr[j]; p < P.col_ptr[j + 1]; ++p)
      if (P.row_ind[p] >= nq) held[j] = 1;
  std::vector<int> map(nq, -1);
  int nf = 0;
  for (int j = 0; j < nq; ++j)
    if (!held[j]) map[j] = nf++;
  Block b;
  b.pattern.n = nf;
  b.pattern.col_ptr.assign(1, 0);
  for (int j = 0; j < nq; ++j) {
    if (map[j] < 0) continue;
    for (int p = P.col_ptr[j]; p < P.col_ptr[j + 1]; ++p) {
      const int i = P.row_ind[p];
      if (i < nq && map[i] >= 0) {
        b.pattern.row_ind.push_back(map[i]);
        b.values.push_back(v[p]);
      }
    }
    b.pattern.col_ptr.push_back(static_cast<int>(b.pattern.row_ind.size()));
  }
  return b;
}

// BoomerAMG-preconditioned CG on the block (rows from the columns: the block is symmetric to
// round-off; hypre takes rows). Returns setup and solve seconds, iterations, the solution.
nlohmann::json amg_solve(const Block& b, const std::vector<double>& rhs, double rtol,
                         std::vector<double>& x) {
  const int n = b.pattern.n;
  std::vector<std::vector<std::pair<int, double>>> rows(n);
  for (int j = 0; j < n; ++j)
    for (int p = b.pattern.col_ptr[j]; p < b.pattern.col_ptr[j + 1]; ++p)
      rows[b.pattern.row_ind[p]].emplace_back(j, b.values[p]);
  const double t0 = now_seconds();
  HYPRE_IJMatrix A;
  HYPRE_IJMatrixCreate(MPI_COMM_WORLD, 0, n - 1, 0, n - 1, &A);
  HYPRE_IJMatrixSetObjectType(A, HYPRE_PARCSR);
  HYPRE_IJMatrixInitialize(A);
  std::vector<HYPRE_BigInt> cols;
  std::vector<double> vals;
  for (HYPRE_BigInt i = 0; i < n; ++i) {
    cols.clear();
    vals.clear();
    for (auto [c, v] : rows[i]) cols.push_back(c), vals.push_back(v);
    HYPRE_Int nc = static_cast<HYPRE_Int>(cols.size());
    HYPRE_IJMatrixSetValues(A, 1, &nc, &i, cols.data(), vals.data());
  }
  HYPRE_IJMatrixAssemble(A);
  HYPRE_ParCSRMatrix pA;
  HYPRE_IJMatrixGetObject(A, reinterpret_cast<void**>(&pA));
  auto vector = [&](const std::vector<double>& values, HYPRE_IJVector& V) {
    HYPRE_IJVectorCreate(MPI_COMM_WORLD, 0, n - 1, &V);
    HYPRE_IJVectorSetObjectType(V, HYPRE_PARCSR);
    HYPRE_IJVectorInitialize(V);
    std::vector<HYPRE_BigInt> idx(n);
    for (int i = 0; i < n; ++i) idx[i] = i;
    HYPRE_IJVectorSetValues(V, n, idx.data(), values.data());
    HYPRE_IJVectorAssemble(V);
    HYPRE_ParVector pv;
    HYPRE_IJVectorGetObject(V, reinterpret_cast<void**>(&pv));
    return pv;
  };
  HYPRE_IJVector B, X;
  HYPRE_ParVector pb = vector(rhs, B), px = vector(std::vector<double>(n, 0.0), X);
  const double t_matrix = now_seconds() - t0;

  HYPRE_Solver pcg, amg;
  HYPRE_ParCSRPCGCreate(MPI_COMM_WORLD, &pcg);
  HYPRE_PCGSetTol(pcg, rtol);
  HYPRE_PCGSetMaxIter(pcg, 2000);
  HYPRE_PCGSetTwoNorm(pcg, 1);
  // the plain systems AMG (no rotations, unknown-based coarsening), aggressive on the first level:
  // the settings this benchmark's rows in docs/performance.md were measured with
  amg = make_elasticity_amg({nullptr, true});
  HYPRE_PCGSetPrecond(pcg, reinterpret_cast<HYPRE_PtrToSolverFcn>(HYPRE_BoomerAMGSolve),
                      reinterpret_cast<HYPRE_PtrToSolverFcn>(HYPRE_BoomerAMGSetup), amg);
  double t = now_seconds();
  HYPRE_ParCSRPCGSetup(pcg, pA, pb, px);
  const double t_setup = now_seconds() - t;
  t = now_seconds();
  HYPRE_ParCSRPCGSolve(pcg, pA, pb, px);
  const double t_solve = now_seconds() - t;
  HYPRE_Int its = 0;
  double res = 0;
  HYPRE_PCGGetNumIterations(pcg, &its);
  HYPRE_PCGGetFinalRelativeResidualNorm(pcg, &res);
  x.assign(n, 0.0);
  std::vector<HYPRE_BigInt> idx(n);
  for (int i = 0; i < n; ++i) idx[i] = i;
  HYPRE_IJVectorGetValues(X, n, idx.data(), x.data());
  HYPRE_BoomerAMGDestroy(amg);
  HYPRE_ParCSRPCGDestroy(pcg);
  HYPRE_IJVectorDestroy(B);
  HYPRE_IJVectorDestroy(X);
  HYPRE_IJMatrixDestroy(A);
  return {{"matrix_seconds", t_matrix},
          {"setup_seconds", t_setup},
          {"solve_seconds", t_solve},
          {"iterations", its},
          {"relative_residual", res}};
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  HYPRE_Init();
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: lsmbs_amg_block CASE.json [--solver amg|umfpack|klu] [--rtol R]\n");
    return 2;
  }
  std::string solver = "amg";
  double rtol = 1e-10;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--solver")) solver = argv[i + 1];
    if (!std::strcmp(argv[i], "--rtol")) rtol = std::stod(argv[i + 1]);
  }
  const Case cs = load_case(argv[1]);
  const Model& m = *cs.model;
  State s = cs.initial;
  s.v.conservativeResize(m.nq());
  s.a.setZero(m.nq());
  s.lambda.setZero(m.nc());
  const auto c = AlphaCoefficients::make(cs.simulation.rho_inf, cs.simulation.h);
  const double k = GeneralizedAlpha::automatic_scaling(m, m.params(), s, c);
  std::vector<double> vals;
  m.iteration_matrix(s, m.params(), {c.beta_p, c.gamma_p, 1}, k, k, vals);
  const Block b = free_block(m.pattern(), vals, m.nq());
  const int n = b.pattern.n;
  std::vector<double> rhs(n);
  for (int i = 0; i < n; ++i) rhs[i] = 1.0 + 0.5 * std::sin(0.37 * i);  // a smooth load
  nlohmann::json J = {{"case", argv[1]},
                      {"solver", solver},
                      {"unknowns", n},
                      {"nonzeros", b.pattern.nnz()},
                      {"rtol", rtol}};
  // AMG first, so that its peak memory is read before the reference LU's
  std::vector<double> x;
  if (solver == "amg") {
    J["amg"] = amg_solve(b, rhs, rtol, x);
    J["peak_rss_kb"] = peak_rss_kb();
  }
  // the direct solution: the timed solver itself (klu, umfpack) or the reference (amg)
  SparseLU lu;
  lu.set_solver(solver == "klu" ? SparseLU::Solver::kKlu : SparseLU::Solver::kUmfpack);
  lu.set_ordering(SparseLU::Ordering::kNestedDissection);
  double t = now_seconds();
  lu.analyze(b.pattern);
  const double t_analyze = now_seconds() - t;
  t = now_seconds();
  const Status st = lu.factor(b.values);
  const double t_factor = now_seconds() - t;
  if (!st.ok() && solver == "amg") {  // no reference: the AMG figures alone
    J["amg"]["difference_from_lu"] = "no LU reference: " + st.message;
    std::printf("%s\n", J.dump().c_str());
    HYPRE_Finalize();
    MPI_Finalize();
    return 0;
  }
  if (!st.ok()) {
    std::fprintf(stderr, "lsmbs_amg_block: %s\n", st.message.c_str());
    return 1;
  }
  std::vector<double> xd = rhs;
  t = now_seconds();
  lu.solve(std::span<double>(xd.data(), xd.size()));
  const double t_solve = now_seconds() - t;
  if (solver == "amg") {
    double num = 0, den = 0;
    for (int i = 0; i < n; ++i) num += (x[i] - xd[i]) * (x[i] - xd[i]), den += xd[i] * xd[i];
    J["amg"]["difference_from_lu"] = std::sqrt(num / den);
  } else {
    J["lu"] = {{"analyze_seconds", t_analyze},
               {"factor_seconds", t_factor},
               {"solve_seconds", t_solve},
               {"factor_nonzeros", lu.factor_nonzeros()}};
    J["peak_rss_kb"] = peak_rss_kb();
  }
  std::printf("%s\n", J.dump().c_str());
  HYPRE_Finalize();
  MPI_Finalize();
  return 0;
}
