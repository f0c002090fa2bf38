// The AMG solver behind SparseLU::Solver::kAmg (linalg/block_amg.hpp) against KLU on the same
// saddle point: an elastic-like block of 3 unknowns per node on a box of nodes (a vector
// Laplacian with coupled directions, symmetric positive definite), one face of nodes tied to a
// "rigid body" of 3 coordinates by constraint rows x_node − r = 0 with zero diagonal, as the
// rigid connections of solid bodies are. The LU's solution is the reference: GMRES on the whole
// matrix must reach it to the residual tolerance, for S and Sᵀ and many right-hand sides.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <random>

#include "lsmbs/linalg/sparse_lu.hpp"

using namespace lsmbs;

namespace {

// a grid of nodes whose factors would fill past SparseLU::auto_amg_fill_threshold()
constexpr int kLargeSide = 40;

struct SaddlePoint {
  CscPattern pattern;
  std::vector<double> values;
  std::vector<int> node_of, direction_of;
  std::vector<double> positions;  // node a at (i, j, k)
  int n = 0, free_nodes = 0;
};

// nx × ny × nz nodes; the x = 0 face is tied to the rigid coordinates r (3 unknowns, mass m_r);
// `skew` adds a nonsymmetric part to the elastic block (a follower load's tangent).
SaddlePoint make(int nx, int ny, int nz, double skew = 0) {
  const int nn = nx * ny * nz, nq = 3 * nn + 3;
  auto node = [&](int i, int j, int k) { return (k * ny + j) * nx + i; };
  std::vector<Eigen::Triplet<double>> t;
  const double D[3][3] = {{2.0, 0.4, 0.1}, {0.4, 2.0, 0.4}, {0.1, 0.4, 2.0}};
  auto couple = [&](int a, int b, double w) {  // w (e_a − e_b)(e_a − e_b)ᵀ ⊗ D
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        const double v = w * D[r][c];
        t.emplace_back(3 * a + r, 3 * a + c, v);
        t.emplace_back(3 * b + r, 3 * b + c, v);
        t.emplace_back(3 * a + r, 3 * b + c, -v + skew * (r - c));
        t.emplace_back(3 * b + r, 3 * a + c, -v - skew * (r - c));
      }
  };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const int a = node(i, j, k);
        if (i + 1 < nx) couple(a, node(i + 1, j, k), 1.0);
        if (j + 1 < ny) couple(a, node(i, j + 1, k), 1.0);
        if (k + 1 < nz) couple(a, node(i, j, k + 1), 1.0);
        for (int r = 0; r < 3; ++r) t.emplace_back(3 * a + r, 3 * a + r, 1e-3);  // "mass"
      }
  for (int r = 0; r < 3; ++r) t.emplace_back(3 * nn + r, 3 * nn + r, 5.0);
  int row = nq;
  const double kscale = 3.0;  // the multipliers' scaling k (eq. 7)
  SaddlePoint s;
  s.node_of.assign(nq + 3 * ny * nz, -1);
  s.direction_of = s.node_of;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j) {
      const int a = node(0, j, k);
      for (int r = 0; r < 3; ++r, ++row) {
        t.emplace_back(row, 3 * a + r, kscale);
        t.emplace_back(3 * a + r, row, kscale);
        t.emplace_back(row, 3 * nn + r, -kscale);
        t.emplace_back(3 * nn + r, row, -kscale);
        t.emplace_back(row, row, 0.0);  // structural diagonal, zero value
      }
    }
  s.n = row;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        s.positions.insert(s.positions.end(), {1.0 * i, 1.0 * j, 1.0 * k});
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 1; i < nx; ++i) {
        const int a = node(i, j, k);
        for (int r = 0; r < 3; ++r) s.node_of[3 * a + r] = a, s.direction_of[3 * a + r] = r;
        ++s.free_nodes;
      }
  Eigen::SparseMatrix<double> A(s.n, s.n);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  s.pattern.n = s.n;
  s.pattern.col_ptr.assign(A.outerIndexPtr(), A.outerIndexPtr() + s.n + 1);
  s.pattern.row_ind.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
  s.values.assign(A.valuePtr(), A.valuePtr() + A.nonZeros());
  return s;
}

double relative_difference(const Mat& a, const Mat& b) { return (a - b).norm() / b.norm(); }

// KLU factorized on s (the reference) and the AMG solver analyzed, not yet factorized (its
// options are set between the two)
void reference_and_amg(const SaddlePoint& s, SparseLU& klu, SparseLU& amg) {
  klu.set_solver(SparseLU::Solver::kKlu);
  klu.analyze(s.pattern);
  ASSERT_TRUE(klu.factor(s.values).ok());
  amg.set_solver(SparseLU::Solver::kAmg);
  amg.set_amg_split(s.node_of, s.direction_of, s.positions);
  amg.analyze(s.pattern);
}

}  // namespace

TEST(BlockAmg, SolvesTheSaddlePointAsTheLUDoesForSAndItsTranspose) {
  if (!SparseLU::amg_available()) GTEST_SKIP() << "this build has no hypre";
  using Shape = BlockAmg::Options::Shape;
  for (Shape shape : {Shape::kThin, Shape::kBulky})
    for (double skew : {0.0, 0.05}) {
      const SaddlePoint s = make(12, 6, 5, skew);
      SparseLU klu, amg;
      reference_and_amg(s, klu, amg);
      EXPECT_EQ(amg.solver_used(), SparseLU::Solver::kAmg);
      amg.amg()->options.shape = shape;
      ASSERT_TRUE(amg.factor(s.values).ok());
      EXPECT_EQ(amg.amg()->counters().bulky, shape == Shape::kBulky);
      EXPECT_EQ(amg.amg()->counters().block_unknowns, 3 * s.free_nodes);
      EXPECT_EQ(amg.amg()->counters().direct_unknowns, s.n - 3 * s.free_nodes);

      std::mt19937 g(7);
      std::normal_distribution<double> u;
      Mat B(s.n, 5);
      for (int i = 0; i < B.size(); ++i) B(i) = u(g);
      Mat X = B, Xr = B;
      amg.solve(X);
      klu.solve(Xr);
      const double d = relative_difference(X, Xr);
      Mat Y = B, Yr = B;
      amg.solve_transpose(std::span<double>(Y.data(), Y.size()), 5);
      klu.solve_transpose(std::span<double>(Yr.data(), Yr.size()), 5);
      const double dt = relative_difference(Y, Yr);
      const auto& c = amg.amg()->counters();
      std::printf(
          "%s, skew %.2f: AMG-GMRES against KLU %.2e (S), %.2e (Sᵀ); %ld solves, at most %d "
          "iterations, worst residual %.1e\n",
          shape == Shape::kBulky ? "bulky" : "thin", skew, d, dt, c.solves, c.max_iterations,
          c.worst_residual);
      EXPECT_EQ(c.fallbacks, 0);
      EXPECT_LT(d, 1e-9);
      EXPECT_LT(dt, 1e-9);
      EXPECT_LE(c.worst_residual, amg.amg()->options.rtol);
      EXPECT_EQ(c.solves, 10);
    }
}

TEST(BlockAmg, TheBlockIsAsManyElementsThickAsItsThinnestSideInAnyOrientation) {
  if (!SparseLU::amg_available()) GTEST_SKIP() << "this build has no hypre";
  // the free nodes of make(nx, ny, nz) span (nx − 2) × (ny − 1) × (nz − 1) unit cells; turned
  // about an arbitrary axis, the count is the same (principal directions, not coordinate axes)
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  // with the tied face's nodes marked held (direction 3 + d), the x = 0 layer counts: 5 × 9 × 8
  // nodes are 4 cells across x, its thinnest side
  struct Grid {
    int nx, ny, nz;
    bool held;
    double layers;
  };
  for (const Grid g : {Grid{12, 6, 5, false, 4}, Grid{12, 6, 2, false, 1}, Grid{5, 9, 8, false, 3},
                       Grid{5, 9, 8, true, 4}})
    for (bool turned : {false, true}) {
      SaddlePoint s = make(g.nx, g.ny, g.nz);
      if (g.held)
        for (int k = 0; k < g.nz; ++k)
          for (int j = 0; j < g.ny; ++j)
            for (int r = 0; r < 3; ++r) {
              const int a = (k * g.ny + j) * g.nx, i = 3 * a + r;
              s.node_of[i] = a, s.direction_of[i] = 3 + r;
            }
      if (turned)
        for (size_t a = 0; a < s.positions.size(); a += 3) {
          Eigen::Map<Eigen::Vector3d> X(&s.positions[a]);
          X = R * Eigen::Vector3d(X);
        }
      SparseLU amg;
      amg.set_solver(SparseLU::Solver::kAmg);
      amg.set_amg_split(s.node_of, s.direction_of, s.positions);
      amg.analyze(s.pattern);
      EXPECT_EQ(amg.amg()->counters().layers, g.layers)  // snapped: exactly the integer
          << g.nx << "×" << g.ny << "×" << g.nz << (g.held ? " held face" : "")
          << (turned ? " turned" : "");
      EXPECT_EQ(amg.amg()->counters().block_unknowns, 3 * s.free_nodes);
      ASSERT_TRUE(amg.factor(s.values).ok());
      EXPECT_EQ(amg.amg()->counters().bulky, g.layers >= amg.amg()->options.bulky_layers);
    }
}

TEST(BlockAmg, ABulkySolveThatDoesNotConvergeStartsAgainAsThinAndKeepsIt) {
  if (!SparseLU::amg_available()) GTEST_SKIP() << "this build has no hypre";
  const SaddlePoint s = make(12, 6, 5);
  SparseLU klu, amg;
  reference_and_amg(s, klu, amg);
  amg.amg()->options.shape = BlockAmg::Options::Shape::kBulky;
  amg.amg()->options.fallback_iterations = 1;  // no solve converges in one iteration
  ASSERT_TRUE(amg.factor(s.values).ok());
  Vec b = Vec::LinSpaced(s.n, -1, 2), x = b, xr = b;
  amg.solve(x);
  klu.solve(xr);
  EXPECT_LT((x - xr).norm() / xr.norm(), 1e-9);
  EXPECT_EQ(amg.amg()->counters().fallbacks, 1);
  EXPECT_FALSE(amg.amg()->counters().bulky);
  // kept through the next factorization and solve
  ASSERT_TRUE(amg.factor(s.values).ok());
  x = b;
  amg.solve(x);
  EXPECT_LT((x - xr).norm() / xr.norm(), 1e-9);
  EXPECT_EQ(amg.amg()->counters().fallbacks, 1);
  EXPECT_FALSE(amg.amg()->counters().bulky);
}

TEST(BlockAmg, AnAllDirectSplitIsTheLUAndSharedAnalysesSolveTheirOwnValues) {
  if (!SparseLU::amg_available()) GTEST_SKIP() << "this build has no hypre";
  SaddlePoint s = make(5, 4, 3);
  SparseLU a, b, klu;
  a.set_solver(SparseLU::Solver::kAmg);
  a.set_amg_split(std::vector<int>(s.n, -1), std::vector<int>(s.n, -1), {});
  a.analyze(s.pattern);
  ASSERT_TRUE(a.factor(s.values).ok());
  EXPECT_EQ(a.amg()->counters().block_unknowns, 0);
  // a second factorization sharing the analysis, of other values (twice the elastic block)
  b.share_analysis(a);
  std::vector<double> v2 = s.values;
  for (auto& v : v2) v *= 2;
  ASSERT_TRUE(b.factor(v2).ok());
  klu.set_solver(SparseLU::Solver::kKlu);
  klu.analyze(s.pattern);
  ASSERT_TRUE(klu.factor(s.values).ok());
  Vec r = Vec::LinSpaced(s.n, -1, 2), x = r, y = r, xr = r;
  a.solve(x);
  b.solve(y);
  klu.solve(xr);
  EXPECT_LT((x - xr).norm() / xr.norm(), 1e-12);
  EXPECT_LT((2 * y - xr).norm() / xr.norm(), 1e-12);  // (2S)⁻¹ r = S⁻¹ r / 2
  EXPECT_LE(a.amg()->counters().max_iterations, 2);   // the preconditioner is the exact LU
}

TEST(BlockAmg, AToleranceNotReachedIsANumericalFailureNotAWrongAnswer) {
  if (!SparseLU::amg_available()) GTEST_SKIP() << "this build has no hypre";
  const SaddlePoint s = make(12, 6, 5);
  SparseLU amg;
  amg.set_solver(SparseLU::Solver::kAmg);
  amg.set_amg_split(s.node_of, s.direction_of, s.positions);
  amg.analyze(s.pattern);
  amg.amg()->options.max_iterations = 2;
  ASSERT_TRUE(amg.factor(s.values).ok());
  Vec b = Vec::Ones(s.n);
  EXPECT_THROW(amg.solve(b), LinearSolveError);
}

TEST(BlockAmg, ASingularDirectBlockNamesItsUnknown) {
  if (!SparseLU::amg_available()) GTEST_SKIP() << "this build has no hypre";
  SaddlePoint s = make(4, 3, 3);
  // the rigid coordinates' columns zeroed (no mass, no tie): r has no pivot
  const int nn = 4 * 3 * 3;
  for (int j = 3 * nn; j < 3 * nn + 3; ++j)
    for (int p = s.pattern.col_ptr[j]; p < s.pattern.col_ptr[j + 1]; ++p) s.values[p] = 0;
  SparseLU amg;
  amg.set_solver(SparseLU::Solver::kAmg);
  amg.set_amg_split(s.node_of, s.direction_of, s.positions);
  amg.analyze(s.pattern);
  const Status st = amg.factor(s.values);
  EXPECT_FALSE(st.ok());
  EXPECT_GE(amg.singular_column(), 0);
  EXPECT_LT(amg.singular_column(), s.n);
}

TEST(BlockAmg, AutomaticChoiceTakesItWhereTheFactorsWouldFillPastTheThreshold) {
  if (!SparseLU::amg_available()) GTEST_SKIP() << "this build has no hypre";
  // KLU's own fill estimate decides, on the pattern alone: a small solid grid stays with an LU, a
  // large one (its AMD-ordered factors past SparseLU::auto_amg_fill_threshold()) goes to AMG; an
  // LU estimate is printed with each
  for (int side : {8, kLargeSide}) {
    const SaddlePoint s = make(side, side, side);
    SparseLU klu;
    klu.set_solver(SparseLU::Solver::kKlu);
    klu.analyze(s.pattern);
    const double fill = klu.estimated_factor_nonzeros();
    SparseLU lu;
    lu.set_amg_split(s.node_of, s.direction_of, s.positions);
    lu.analyze(s.pattern);
    std::printf("%d³ nodes, %d unknowns: estimated fill %.3g, automatic choice %s\n", side, s.n,
                fill, SparseLU::solver_name(lu.solver_used()));
    EXPECT_EQ(lu.solver_used() == SparseLU::Solver::kAmg,
              fill > SparseLU::auto_amg_fill_threshold());
    EXPECT_EQ(lu.solver_used() == SparseLU::Solver::kAmg, side == kLargeSide);
  }
}
