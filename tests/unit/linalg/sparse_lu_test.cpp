// SparseLU (KLU) against a dense LU of the same matrix; refactorization and multi-RHS solves.
#include "lsmbs/linalg/sparse_lu.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

using namespace lsmbs;

namespace {
// Random sparse pattern (blocks) with a dominant diagonal.
struct Problem {
  BlockAssembler asmb;
  std::vector<double> vals;
};
Problem make(int n, unsigned seed) {
  SparsityBuilder sb(n);
  std::mt19937 g(seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::vector<std::vector<int>> blocks;
  for (int b = 0; b < 3 * n; ++b) {
    std::vector<int> d = {pick(g), pick(g), pick(g)};
    sb.add_block(d, d);
    blocks.push_back(d);
  }
  sb.add_diagonal();
  Problem p{BlockAssembler(sb.finalize()), {}};
  p.vals.assign(p.asmb.pattern().nnz(), 0.0);
  std::uniform_real_distribution<double> u(-1, 1);
  for (size_t b = 0; b < blocks.size(); ++b) {
    Eigen::Matrix3d m;
    for (int i = 0; i < 9; ++i) m(i) = u(g);
    p.asmb.add(p.vals, static_cast<int>(b), m);
  }
  for (int i = 0; i < n; ++i) p.asmb.add_diagonal(p.vals, i, 10.0);
  return p;
}
}  // namespace

TEST(SparseLU, SolvesLikeADenseLUWithManyRightHandSides) {
  auto p = make(60, 3);
  SparseLU lu;
  lu.analyze(p.asmb.pattern());
  ASSERT_TRUE(lu.factor(p.vals).ok());
  const Mat A = Mat(p.asmb.to_sparse(p.vals));
  Mat B = Mat::Random(60, 4), X = B;
  lu.solve(X);
  const Mat Xd = A.partialPivLu().solve(B);
  EXPECT_LT((X - Xd).norm() / Xd.norm(), 1e-12);
  Vec b = Vec::Random(60), x = b;
  lu.solve_transpose(std::span<double>(x.data(), 60));
  EXPECT_LT((A.transpose() * x - b).norm() / b.norm(), 1e-12);
}

TEST(SparseLU, RefactorizationOfNewValuesReusesTheSymbolicAnalysis) {
  auto p = make(40, 5);
  SparseLU lu;
  lu.analyze(p.asmb.pattern());
  ASSERT_TRUE(lu.factor(p.vals).ok());
  for (auto& v : p.vals) v *= 1.5;
  for (int i = 0; i < 40; ++i) p.asmb.add_diagonal(p.vals, i, 0.3 * i);
  ASSERT_TRUE(lu.factor(p.vals).ok());
  EXPECT_EQ(lu.counters().symbolic, 1);
  EXPECT_EQ(lu.counters().refactorizations, 1);
  const Mat A = Mat(p.asmb.to_sparse(p.vals));
  Vec b = Vec::Random(40), x = b;
  lu.solve(x);
  EXPECT_LT((A * x - b).norm() / b.norm(), 1e-12);
}

TEST(SparseLU, SingularMatrixIsReportedWithItsColumn) {
  SparsityBuilder sb(3);
  sb.add_diagonal();
  BlockAssembler a(sb.finalize());
  std::vector<double> v(a.pattern().nnz(), 0.0);
  a.add_diagonal(v, 0, 1.0);
  a.add_diagonal(v, 2, 1.0);
  SparseLU lu;
  lu.analyze(a.pattern());
  const auto st = lu.factor(v);
  EXPECT_FALSE(st.ok());
  EXPECT_EQ(lu.singular_column(), 1);
}

// Nested-dissection ordering (METIS through CHOLMOD, KLU's user-ordering hook): the same
// solution as a dense LU, and on the 5-point Laplacian of a 60 × 60 grid less fill than AMD —
// the property it is there for (nested dissection is asymptotically optimal on 2-D grids).
TEST(SparseLU, NestedDissectionSolvesLikeADenseLU) {
  auto p = make(80, 7);
  SparseLU lu;
  lu.set_ordering(SparseLU::Ordering::kNestedDissection);
  lu.analyze(p.asmb.pattern());
  ASSERT_TRUE(lu.factor(p.vals).ok());
  const Mat A = Mat(p.asmb.to_sparse(p.vals));
  Mat B = Mat::Random(80, 3), X = B;
  lu.solve(X);
  EXPECT_LT((X - A.partialPivLu().solve(B)).norm() / X.norm(), 1e-12);
}

TEST(SparseLU, NestedDissectionFillsLessThanAmdOnALargeGrid) {
  const int m = 60, n = m * m;
  SparsityBuilder sb(n);
  auto id = [&](int i, int j) { return i * m + j; };
  std::vector<std::pair<int, int>> edges;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      if (i + 1 < m) edges.emplace_back(id(i, j), id(i + 1, j));
      if (j + 1 < m) edges.emplace_back(id(i, j), id(i, j + 1));
    }
  for (auto [a, b] : edges) {
    std::vector<int> d = {a, b};
    sb.add_block(d, d);
  }
  sb.add_diagonal();
  BlockAssembler asmb(sb.finalize());
  std::vector<double> vals(asmb.pattern().nnz(), 0.0);
  for (size_t e = 0; e < edges.size(); ++e)
    asmb.add(vals, static_cast<int>(e), Eigen::Matrix2d{{1, -1}, {-1, 1}});
  for (int i = 0; i < n; ++i) asmb.add_diagonal(vals, i, 1e-3);
  long fill[2];
  for (int o = 0; o < 2; ++o) {
    SparseLU lu;
    lu.set_ordering(o ? SparseLU::Ordering::kNestedDissection : SparseLU::Ordering::kAmd);
    lu.analyze(asmb.pattern());
    ASSERT_TRUE(lu.factor(vals).ok());
    fill[o] = lu.factor_nonzeros();
    Vec b = Vec::Ones(n), x = b;
    lu.solve(x);
    const SpMat A = asmb.to_sparse(vals);
    EXPECT_LT((A * x - b).norm() / b.norm(), 1e-10);
  }
  std::printf("5-point Laplacian %d x %d: nnz(L+U) AMD %ld, nested dissection %ld\n", m, m, fill[0],
              fill[1]);
  EXPECT_LT(fill[1], fill[0]);
}

// Two numeric factorizations on one symbolic analysis (the integrator's double buffer for
// concurrent sensitivity observers): each solves its own matrix like a dense LU, and neither
// refactorization disturbs the other.
TEST(SparseLU, SharedAnalysisKeepsTwoIndependentFactorizations) {
  auto p = make(50, 11), q = p;
  for (auto& v : q.vals) v *= -0.7;
  for (int i = 0; i < 50; ++i) q.asmb.add_diagonal(q.vals, i, 0.1 * i);
  SparseLU a, b;
  a.analyze(p.asmb.pattern());
  b.share_analysis(a);
  ASSERT_TRUE(a.factor(p.vals).ok());
  ASSERT_TRUE(b.factor(q.vals).ok());
  ASSERT_TRUE(a.factor(p.vals).ok());  // refactorization of a after b's
  EXPECT_EQ(a.counters().symbolic, 1);
  EXPECT_EQ(b.counters().symbolic, 0) << "no second symbolic analysis";
  const Mat A = Mat(p.asmb.to_sparse(p.vals)), B = Mat(q.asmb.to_sparse(q.vals));
  Mat R = Mat::Random(50, 3), X = R, Y = R;
  a.solve(X);
  b.solve(Y);
  EXPECT_LT((X - A.partialPivLu().solve(R)).norm() / X.norm(), 1e-12);
  EXPECT_LT((Y - B.partialPivLu().solve(R)).norm() / Y.norm(), 1e-12);
  EXPECT_GT((X - Y).norm(), 1e-3 * X.norm()) << "different matrices";
}

// UMFPACK's multifrontal LU behind the same interface: with AMD and with METIS, A x = b and
// Aᵀ x = b for several right-hand sides against a dense LU of the same matrix, twice (a second
// numeric factorization of new values on the one symbolic analysis).
TEST(SparseLU, UmfpackSolvesLikeADenseLU) {
  for (auto o : {SparseLU::Ordering::kAmd, SparseLU::Ordering::kNestedDissection}) {
    auto p = make(90, 13);
    SparseLU lu;
    lu.set_solver(SparseLU::Solver::kUmfpack);
    lu.set_ordering(o);
    lu.analyze(p.asmb.pattern());
    EXPECT_EQ(lu.solver_used(), SparseLU::Solver::kUmfpack);
    for (int round = 0; round < 2; ++round) {
      ASSERT_TRUE(lu.factor(p.vals).ok());
      const Mat A = Mat(p.asmb.to_sparse(p.vals));
      Mat B = Mat::Random(90, 3), X = B, Y = B;
      lu.solve(X);
      lu.solve_transpose(std::span<double>(Y.data(), Y.size()), 3);
      EXPECT_LT((X - A.partialPivLu().solve(B)).norm() / X.norm(), 1e-12);
      EXPECT_LT((Y - A.transpose().partialPivLu().solve(B)).norm() / Y.norm(), 1e-12);
      EXPECT_GT(lu.factor_nonzeros(), p.asmb.pattern().n);
      EXPECT_GT(lu.rcond(), 0.0);
      for (auto& v : p.vals) v *= -1.3;
      for (int i = 0; i < 90; ++i) p.asmb.add_diagonal(p.vals, i, 0.2 * i);
    }
    EXPECT_EQ(lu.counters().symbolic, 1);
    EXPECT_EQ(lu.counters().full_factorizations, 2);
  }
}

// The singular-matrix diagnostics do not depend on the solver: UMFPACK's failure names the
// column KLU names.
TEST(SparseLU, UmfpackReportsTheSingularColumnAsKluDoes) {
  SparsityBuilder sb(4);
  sb.add_diagonal();
  BlockAssembler a(sb.finalize());
  std::vector<double> v(a.pattern().nnz(), 0.0);
  for (int i : {0, 1, 3}) a.add_diagonal(v, i, 1.0 + i);
  SparseLU lu;
  lu.set_solver(SparseLU::Solver::kUmfpack);
  lu.analyze(a.pattern());
  EXPECT_FALSE(lu.factor(v).ok());
  EXPECT_EQ(lu.singular_column(), 2);
  EXPECT_FALSE(lu.factored());
}

TEST(SparseLU, UmfpackSharedAnalysisKeepsTwoIndependentFactorizations) {
  auto p = make(50, 17), q = p;
  for (auto& v : q.vals) v *= 0.6;
  for (int i = 0; i < 50; ++i) q.asmb.add_diagonal(q.vals, i, -0.1 * i);
  SparseLU a, b;
  a.set_solver(SparseLU::Solver::kUmfpack);
  a.analyze(p.asmb.pattern());
  b.share_analysis(a);
  EXPECT_EQ(b.solver_used(), SparseLU::Solver::kUmfpack);
  ASSERT_TRUE(a.factor(p.vals).ok());
  ASSERT_TRUE(b.factor(q.vals).ok());
  const Mat A = Mat(p.asmb.to_sparse(p.vals)), B = Mat(q.asmb.to_sparse(q.vals));
  Mat R = Mat::Random(50, 2), X = R, Y = R;
  a.solve(X);
  b.solve(Y);
  EXPECT_LT((X - A.partialPivLu().solve(R)).norm() / X.norm(), 1e-12);
  EXPECT_LT((Y - B.partialPivLu().solve(R)).norm() / Y.norm(), 1e-12);
  EXPECT_EQ(b.counters().symbolic, 0);
}

// The automatic choice: KLU for a pattern that fills little (a 2-D grid of 3,600 unknowns),
// UMFPACK for one whose KLU factors would fill past the threshold (the 7-point Laplacian of a
// 3-D grid of 24³ unknowns); both solve the 3-D system to the residual a direct solver gives.
TEST(SparseLU, AutomaticChoiceFollowsTheEstimatedFill) {
  auto grid = [](int m, int dim) {
    const int n = dim == 2 ? m * m : m * m * m;
    SparsityBuilder sb(n);
    std::vector<std::pair<int, int>> edges;
    for (int k = 0; k < n; ++k) {
      const int i = k % m, j = (k / m) % m, l = k / (m * m);
      if (i + 1 < m) edges.emplace_back(k, k + 1);
      if (j + 1 < m) edges.emplace_back(k, k + m);
      if (dim == 3 && l + 1 < m) edges.emplace_back(k, k + m * m);
    }
    for (auto [a, b] : edges) {
      std::vector<int> d = {a, b};
      sb.add_block(d, d);
    }
    sb.add_diagonal();
    auto asmb = std::make_unique<BlockAssembler>(sb.finalize());
    std::vector<double> vals(asmb->pattern().nnz(), 0.0);
    for (size_t e = 0; e < edges.size(); ++e)
      asmb->add(vals, static_cast<int>(e), Eigen::Matrix2d{{1, -1}, {-1, 1}});
    for (int i = 0; i < n; ++i) asmb->add_diagonal(vals, i, 1e-2);
    return std::make_pair(std::move(asmb), vals);
  };
  {
    auto [asmb, vals] = grid(60, 2);
    SparseLU lu;
    lu.analyze(asmb->pattern());
    EXPECT_EQ(lu.solver_used(), SparseLU::Solver::kKlu);
    EXPECT_LT(lu.estimated_factor_nonzeros(), SparseLU::auto_fill_threshold());
  }
  auto [asmb, vals] = grid(24, 3);
  SparseLU lu;
  lu.analyze(asmb->pattern());
  EXPECT_GT(lu.estimated_factor_nonzeros(), SparseLU::auto_fill_threshold());
  EXPECT_EQ(lu.solver_used(), SparseLU::Solver::kUmfpack);
  ASSERT_TRUE(lu.factor(vals).ok());
  const int n = asmb->pattern().n;
  Vec b = Vec::LinSpaced(n, -1, 1), x = b;
  lu.solve(x);
  const SpMat A = asmb->to_sparse(vals);
  SparseLU klu;
  klu.set_solver(SparseLU::Solver::kKlu);
  klu.analyze(asmb->pattern());
  ASSERT_TRUE(klu.factor(vals).ok());
  Vec y = b;
  klu.solve(y);
  std::printf("3-D grid 24^3: residual UMFPACK %.2e, KLU %.2e; |x_umf - x_klu| / |x| %.2e\n",
              (A * x - b).norm() / b.norm(), (A * y - b).norm() / b.norm(),
              (x - y).norm() / y.norm());
  EXPECT_LT((A * x - b).norm() / b.norm(), 1e-12);
}
