// Non-negative least squares (the KKT report's multipliers) against the exhaustive solution:
// for a small problem the NNLS solution is the best of the unconstrained least-squares
// solutions on every subset of columns that comes out non-negative.
#include "lsmbs/optimization/kkt.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

using namespace lsmbs;

namespace {

Vec exhaustive_nnls(const Mat& A, const Vec& b) {
  const Eigen::Index n = A.cols();
  Vec best = Vec::Zero(n);
  double best_r = (b).squaredNorm();
  for (unsigned mask = 1; mask < (1u << n); ++mask) {
    std::vector<Eigen::Index> idx;
    for (Eigen::Index j = 0; j < n; ++j)
      if (mask & (1u << j)) idx.push_back(j);
    Mat As(A.rows(), static_cast<Eigen::Index>(idx.size()));
    for (size_t k = 0; k < idx.size(); ++k) As.col(static_cast<Eigen::Index>(k)) = A.col(idx[k]);
    const Vec z = As.colPivHouseholderQr().solve(b);
    if ((z.array() < 0).any()) continue;
    Vec x = Vec::Zero(n);
    for (size_t k = 0; k < idx.size(); ++k) x[idx[k]] = z[static_cast<Eigen::Index>(k)];
    const double r = (A * x - b).squaredNorm();
    if (r < best_r) best_r = r, best = x;
  }
  return best;
}

}  // namespace

TEST(NonnegativeLeastSquares, ClosedForms) {
  // identity: the positive part of b
  const Vec x =
      nonnegative_least_squares(Mat::Identity(3, 3), Vec((Vec(3) << 1, -2, 0.5).finished()));
  EXPECT_NEAR(x[0], 1, 1e-15);
  EXPECT_EQ(x[1], 0);
  EXPECT_NEAR(x[2], 0.5, 1e-15);
  // one column: max(0, a·b / a·a)
  Mat a(2, 1);
  a << 3, 4;
  EXPECT_NEAR(nonnegative_least_squares(a, Vec((Vec(2) << 3, 4).finished()))[0], 1, 1e-15);
  EXPECT_EQ(nonnegative_least_squares(a, Vec((Vec(2) << -3, -4).finished()))[0], 0);
}

TEST(NonnegativeLeastSquares, AgreesWithTheExhaustiveSolutionOnRandomProblems) {
  std::mt19937_64 gen(7);
  std::normal_distribution<double> N(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const int rows = 2 + trial % 7, cols = 1 + trial % 5;
    Mat A(rows, cols);
    Vec b(rows);
    for (int i = 0; i < rows; ++i) {
      b[i] = N(gen);
      for (int j = 0; j < cols; ++j) A(i, j) = N(gen);
    }
    const Vec x = nonnegative_least_squares(A, b), ref = exhaustive_nnls(A, b);
    EXPECT_TRUE((x.array() >= 0).all());
    EXPECT_NEAR((A * x - b).squaredNorm(), (A * ref - b).squaredNorm(),
                1e-10 * (1 + b.squaredNorm()))
        << "trial " << trial;
  }
}
