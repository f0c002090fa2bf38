// The SUNLinearSolver that IdasGGL uses (sun::new_sparse_lu_solver: SparseLU with
// SUNLinSol_KLU's policy) against SUNDIALS' own SUNLinSol_KLU on the same sequence of GGL
// Jacobians — well-conditioned ones (refactorizations with the first pivot sequence), a badly
// scaled one (KLU's condest asks for fresh pivoting), a re-initialization (IDAS after
// IDAReInit), and the history-free mode — and against a dense LU of each matrix. The solutions
// must be the same to the bit: the IDAS reference runs before and after the switch to SparseLU
// are compared bit for bit.
#include <gtest/gtest.h>
#include <sunlinsol/sunlinsol_klu.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>

#include "lsmbs/integrators/ggl_system.hpp"
#include "lsmbs/integrators/sundials_handles.hpp"
#include "support/pendulum.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;

namespace {

struct Solvers {
  sun::Context ctx;
  sun::Vector x, b;
  sun::Matrix A;
  sun::LinearSolver ours, klu;
  Solvers(int n, long nnz, double pivot_tolerance, bool fresh_each_setup) {
    EXPECT_TRUE(ctx.create());
    x = sun::new_vector(n, ctx);
    b = sun::new_vector(n, ctx);
    A.reset(SUNSparseMatrix(n, n, nnz, CSC_MAT, ctx.get()));
    ours = sun::new_sparse_lu_solver(ctx, pivot_tolerance, fresh_each_setup);
    klu.reset(SUNLinSol_KLU(x.get(), A.get(), ctx.get()));
    SUNLinSol_KLUGetCommon(klu.get())->tol = pivot_tolerance;
    EXPECT_EQ(SUNLinSolInitialize(ours.get()), 0);
    EXPECT_EQ(SUNLinSolInitialize(klu.get()), 0);
  }
  // Sets up both solvers with J (as IDAS does after a Jacobian evaluation) and solves J x = rhs;
  // `fresh_klu`: SUNLinSol_KLU re-initialized first (what the history-free mode replaces).
  void step(const SpMat& J, const Vec& rhs, bool fresh_klu, Vec& x_ours, Vec& x_klu) {
    sun::copy_to(J, A.get());
    if (fresh_klu)
      SUNLinSol_KLUReInit(klu.get(), A.get(), SM_NNZ_S(A.get()), SUNKLU_REINIT_PARTIAL);
    ASSERT_EQ(SUNLinSolSetup(ours.get(), A.get()), 0);
    ASSERT_EQ(SUNLinSolSetup(klu.get(), A.get()), 0);
    sun::map(b.get()) = rhs;
    ASSERT_EQ(SUNLinSolSolve(ours.get(), A.get(), x.get(), b.get(), 0.0), 0);
    x_ours = sun::map(x.get());
    ASSERT_EQ(SUNLinSolSolve(klu.get(), A.get(), x.get(), b.get(), 0.0), 0);
    x_klu = sun::map(x.get());
  }
};

// GGL Jacobians F_y + c_j F_ẏ of the pendulum along a sequence of points and c_j.
struct Jacobians {
  Case cs = test::make_case(test::Pendulum{}.json(1e-3));
  GglSystem ggl{*cs.model};
  std::mt19937 g{3};
  std::uniform_real_distribution<double> u{-1, 1};
  Vec y, yp;
  Jacobians() {
    const int nq = cs.model->nq(), nc = cs.model->nc();
    y.resize(ggl.size());
    yp.setZero(ggl.size());
    y << cs.initial.q, Vec::Zero(nq), Vec::Zero(nc), Vec::Zero(nc);
    ggl.set_scales({.s1 = 30, .s3 = 3e4, .s4 = 30});
  }
  SpMat next(double cj) {
    for (int i = 0; i < ggl.size(); ++i) y[i] += 1e-2 * u(g);
    return ggl.jacobian(cs.model->params(), 0.1, cj, y.data(), yp.data());
  }
};

void expect_same_bits_and_right(const SpMat& J, const Vec& rhs, const Vec& x_ours, const Vec& x_klu,
                                const char* what) {
  for (Eigen::Index i = 0; i < x_ours.size(); ++i)
    EXPECT_EQ(x_ours[i], x_klu[i]) << what << ", entry " << i;
  const Vec x_dense = Mat(J).fullPivLu().solve(rhs);
  EXPECT_LT((x_ours - x_dense).norm(), 1e-9 * x_dense.norm()) << what;
}

}  // namespace

TEST(SparseLuLinearSolver, SolvesAsSunLinSolKluToTheBitThroughRefactorizationsAndFreshPivoting) {
  Jacobians jac;
  const SpMat J0 = jac.next(1e4);
  Solvers s(jac.ggl.size(), J0.nonZeros(), 1.0, false);
  Vec rhs = Vec::LinSpaced(jac.ggl.size(), -1.0, 2.0), a, b;
  for (int k = 0; k < 6; ++k) {  // first a fresh factorization, then refactorizations
    const SpMat J = jac.next(1e4 * (1 + k));
    s.step(J, rhs, false, a, b);
    expect_same_bits_and_right(J, rhs, a, b, "well conditioned");
  }
  // The μ columns scaled down by 1e-13 (KLU's row scaling cannot undo it): KLU's rcond falls
  // below ε^(2/3), its condest confirms, and both factorize again with fresh pivoting.
  SpMat J = jac.next(2e4);
  for (int j = J.cols() - jac.cs.model->nc(); j < J.cols(); ++j) J.col(j) *= 1e-13;
  s.step(J, rhs, false, a, b);
  const double eps23 = std::pow(std::numeric_limits<double>::epsilon(), 2.0 / 3.0);
  EXPECT_LT(SUNLinSol_KLUGetCommon(s.klu.get())->rcond, eps23) << "the condest path is exercised";
  EXPECT_GT(SUNLinSol_KLUGetCommon(s.klu.get())->condest, 1 / eps23)
      << "the fresh pivoting is exercised";
  for (Eigen::Index i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]) << "badly scaled, entry " << i;
  EXPECT_TRUE(a.allFinite());
  // IDAS re-initialized (IDAReInit): the next setup factorizes with fresh pivoting.
  ASSERT_EQ(SUNLinSolInitialize(s.ours.get()), 0);
  ASSERT_EQ(SUNLinSolInitialize(s.klu.get()), 0);
  for (int k = 0; k < 3; ++k) {
    J = jac.next(5e3);
    s.step(J, rhs, false, a, b);
    expect_same_bits_and_right(J, rhs, a, b, "after initialize");
  }
}

TEST(SparseLuLinearSolver, HistoryFreeModeFactorizesEverySetupWithFreshPivoting) {
  Jacobians jac;
  const SpMat J0 = jac.next(1e4);
  Solvers s(jac.ggl.size(), J0.nonZeros(), 1.0, true);
  Vec rhs = Vec::LinSpaced(jac.ggl.size(), 0.5, -3.0), a, b;
  for (int k = 0; k < 5; ++k) {
    const SpMat J = jac.next(1e4 / (1 + k));
    s.step(J, rhs, true, a, b);
    expect_same_bits_and_right(J, rhs, a, b, "history-free");
  }
}
