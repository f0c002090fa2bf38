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
