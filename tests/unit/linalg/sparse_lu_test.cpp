// SparseLU (KLU) against a dense LU of the same matrix; refactorization and multi-RHS solves.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "lsmbs/linalg/sparse_lu.hpp"

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
