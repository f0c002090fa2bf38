// Svanberg's classic MMA against published optima, a closed-form subproblem and NLopt's MMA.
#include <gtest/gtest.h>
#include <nlopt.h>

#include <Eigen/QR>
#include <cmath>
#include <functional>

#include "lsmbs/optimization/mma_classic.hpp"

using lsmbs::Mat;
using lsmbs::Vec;

namespace {

// f0(x), ∇f0, f(x) (m), ∇f (m × n)
struct TestProblem {
  int n, m;
  Vec xmin, xmax, x0;
  std::function<double(const Vec&, Vec&, Vec&, Mat&)> eval;
};

// Svanberg (1987), section 7.1: cantilever beam of five square hollow segments.
// minimize 0.0624 Σ x_j  s.t.  61/x1³ + 37/x2³ + 19/x3³ + 7/x4³ + 1/x5³ ≤ 1,  1 ≤ x ≤ 10.
// Published optimum: f = 1.340, x = (6.016, 5.309, 4.494, 3.502, 2.153).
TestProblem cantilever() {
  TestProblem t{5, 1, Vec::Constant(5, 1.0), Vec::Constant(5, 10.0), Vec::Constant(5, 5.0), {}};
  t.eval = [](const Vec& x, Vec& df0, Vec& f, Mat& df) {
    const double c[5] = {61, 37, 19, 7, 1};
    df0 = Vec::Constant(5, 0.0624);
    f.resize(1);
    df.resize(1, 5);
    f[0] = -1;
    for (int j = 0; j < 5; ++j) {
      f[0] += c[j] / std::pow(x[j], 3);
      df(0, j) = -3 * c[j] / std::pow(x[j], 4);
    }
    return 0.0624 * x.sum();
  };
  return t;
}

// Svanberg's "toy" problem of his MMA notes (2007): minimize x1² + x2² + x3² s.t.
// (x1−5)² + (x2−2)² + (x3−1)² ≤ 9, (x1−3)² + (x2−4)² + (x3−3)² ≤ 9, 0 ≤ x ≤ 5, x0 = (4, 3, 2).
TestProblem toy() {
  TestProblem t{3, 2, Vec::Zero(3), Vec::Constant(3, 5.0), Vec(3), {}};
  t.x0 << 4, 3, 2;
  t.eval = [](const Vec& x, Vec& df0, Vec& f, Mat& df) {
    df0 = 2 * x;
    Vec c1(3), c2(3);
    c1 << 5, 2, 1;
    c2 << 3, 4, 3;
    f.resize(2);
    df.resize(2, 3);
    f[0] = (x - c1).squaredNorm() - 9;
    f[1] = (x - c2).squaredNorm() - 9;
    df.row(0) = 2 * (x - c1).transpose();
    df.row(1) = 2 * (x - c2).transpose();
    return x.squaredNorm();
  };
  return t;
}

struct Outcome {
  Vec x;
  double f;
  int iterations;
};

Outcome run_classic(const TestProblem& t, int max_iter = 200, double tol = 1e-9) {
  lsmbs::MmaClassic mma(t.xmin, t.xmax, t.m);
  Vec x = t.x0, df0, f;
  Mat df;
  double fv = t.eval(x, df0, f, df);
  int k = 0;
  for (; k < max_iter; ++k) {
    const Vec xn = mma.step(x, df0, f, df);
    const double change = (xn - x).cwiseAbs().maxCoeff();
    x = xn;
    fv = t.eval(x, df0, f, df);
    if (change < tol) break;
  }
  return {x, fv, k + 1};
}

Outcome run_nlopt(const TestProblem& t) {
  struct Data {
    const TestProblem* t;
  } data{&t};
  nlopt_opt opt = nlopt_create(NLOPT_LD_MMA, t.n);
  nlopt_set_lower_bounds(opt, t.xmin.data());
  nlopt_set_upper_bounds(opt, t.xmax.data());
  nlopt_set_min_objective(
      opt,
      [](unsigned n, const double* x, double* g, void* d) {
        Vec df0, f;
        Mat df;
        const double v = static_cast<Data*>(d)->t->eval(Eigen::Map<const Vec>(x, n), df0, f, df);
        if (g) Eigen::Map<Vec>(g, n) = df0;
        return v;
      },
      &data);
  std::vector<double> tol(t.m, 0.0);
  nlopt_add_inequality_mconstraint(
      opt, t.m,
      [](unsigned m, double* r, unsigned n, const double* x, double* g, void* d) {
        Vec df0, f;
        Mat df;
        static_cast<Data*>(d)->t->eval(Eigen::Map<const Vec>(x, n), df0, f, df);
        for (unsigned i = 0; i < m; ++i) {
          r[i] = f[i];
          if (g)
            for (unsigned j = 0; j < n; ++j) g[i * n + j] = df(i, j);
        }
      },
      &data, tol.data());
  nlopt_set_xtol_rel(opt, 1e-10);
  nlopt_set_maxeval(opt, 5000);
  std::vector<double> x(t.x0.data(), t.x0.data() + t.n);
  double f = 0;
  nlopt_optimize(opt, x.data(), &f);
  int evals = nlopt_get_numevals(opt);
  nlopt_destroy(opt);
  return {Eigen::Map<Vec>(x.data(), t.n), f, evals};
}

}  // namespace

TEST(MmaSubproblem, OneVariableClosedForm) {
  // minimize p/(u − x) + q/(x − l) with an inactive constraint: x* = (l √p + u √q)/(√p + √q)
  lsmbs::MmaSubproblem sp;
  const double l = -1, u = 2, p = 0.3, q = 1.7;
  sp.low = Vec::Constant(1, l), sp.upp = Vec::Constant(1, u);
  sp.alpha = Vec::Constant(1, -0.9), sp.beta = Vec::Constant(1, 1.9);
  sp.p0 = Vec::Constant(1, p), sp.q0 = Vec::Constant(1, q);
  sp.P = Mat::Constant(1, 1, 1e-3), sp.Q = Mat::Constant(1, 1, 1e-3);
  sp.b = Vec::Constant(1, 10.0);  // far from active
  sp.a = Vec::Zero(1), sp.c = Vec::Constant(1, 1000), sp.d = Vec::Ones(1);
  const auto s = lsmbs::solve_mma_subproblem(sp);
  const double exact = (l * std::sqrt(p) + u * std::sqrt(q)) / (std::sqrt(p) + std::sqrt(q));
  EXPECT_NEAR(s.x[0], exact, 1e-6);
  EXPECT_LT(s.lam[0], 1e-6);
  // now the bound β binds: the solution is β
  sp.beta = Vec::Constant(1, 0.5);
  EXPECT_NEAR(lsmbs::solve_mma_subproblem(sp).x[0], 0.5, 1e-6);
}

TEST(MmaClassic, SvanbergCantileverPublishedOptimum) {
  const auto t = cantilever();
  const Outcome r = run_classic(t);
  EXPECT_NEAR(r.f, 1.340, 5e-4);
  const double xs[5] = {6.016, 5.309, 4.494, 3.502, 2.153};
  for (int j = 0; j < 5; ++j) EXPECT_NEAR(r.x[j], xs[j], 2e-3) << j;
  // the constraint is active
  Vec df0, f;
  Mat df;
  t.eval(r.x, df0, f, df);
  EXPECT_NEAR(f[0], 0, 1e-6);
  // NLopt's MMA reaches the same point
  const Outcome nl = run_nlopt(t);
  EXPECT_NEAR((nl.x - r.x).cwiseAbs().maxCoeff(), 0, 1e-4);
  std::printf(
      "cantilever: classic MMA %d iterations, f = %.6f; NLopt LD_MMA %d evaluations, f = %.6f\n",
      r.iterations, r.f, nl.iterations, nl.f);
}

TEST(MmaClassic, ToyProblemAgreesWithNloptAndKkt) {
  const auto t = toy();
  const Outcome r = run_classic(t);
  const Outcome nl = run_nlopt(t);
  EXPECT_NEAR((nl.x - r.x).cwiseAbs().maxCoeff(), 0, 1e-5);
  EXPECT_NEAR(r.f, nl.f, 1e-6);
  // KKT: both constraints active, ∇f0 + Σ λ_i ∇f_i = 0 with λ ≥ 0 (least squares for λ)
  Vec df0, f;
  Mat df;
  t.eval(r.x, df0, f, df);
  EXPECT_NEAR(f[0], 0, 1e-6);  // the interior-point relaxation ends at 1e-7
  EXPECT_NEAR(f[1], 0, 1e-6);
  const Vec lam = df.transpose().colPivHouseholderQr().solve(-df0);
  EXPECT_GT(lam.minCoeff(), 0);
  EXPECT_LT((df0 + df.transpose() * lam).norm(), 1e-6);
  std::printf("toy: classic MMA %d iterations, x = (%.6f, %.6f, %.6f); NLopt %d evaluations\n",
              r.iterations, r.x[0], r.x[1], r.x[2], nl.iterations);
}

TEST(MmaClassic, StepDoesNotScaleWithTheGradient) {
  // minimize g·x on [0, 1] from 0 (g < 0) with a constant constraint f = −1 (zero gradient: its
  // approximation carries only the regularization and never binds). The one-variable subproblem
  // min p/(u − x) + q/(x − l) then has the minimizer x* = (l √p + u √q)/(√p + √q), clipped to
  // β = min(u − 0.1 (u − x), x + 0.5, 1), with p = r (u − x)², q = (|g| + r)(x − l)²,
  // r = 0.001 |g| + raa0 (raa0 = 1e-5). Asymptotes x ± 0.5 in iterations 1 and 2, then widened by
  // 1.2 while x keeps its direction. By hand:
  //  * g = −1e-2 (√(p/q) = 0.045): x* beyond β each time: x = 0.45, 0.9 (asymptotes reset), then
  //    l = 0.3, u = 1.5, β = 1: three iterations;
  //  * g = −1e-4 (raa0 is 10 % of |g|: √(p/q) = 0.303, x* inside the box): x = 0.2675, 0.535, then
  //    (l, u) = (−0.065, 1.135): 0.856, then (0.136, 1.576): 1 — four iterations.
  // A step proportional to the gradient would need a hundred times more for the smaller one.
  const std::vector<double> by_hand[2] = {{0.45, 0.9, 1.0}, {0.2675, 0.535, 0.856, 1.0}};
  int c = 0;
  for (double g : {-1e-2, -1e-4}) {
    TestProblem t{1, 1, Vec::Zero(1), Vec::Ones(1), Vec::Zero(1), {}};
    t.eval = [g](const Vec& x, Vec& df0, Vec& f, Mat& df) {
      df0 = Vec::Constant(1, g);
      f = Vec::Constant(1, -1.0);
      df = Mat::Zero(1, 1);
      return g * x[0];
    };
    lsmbs::MmaClassic mma(t.xmin, t.xmax, t.m);
    Vec x = t.x0, df0, f;
    Mat df;
    std::vector<double> path;
    while (x[0] < 0.99 && path.size() < 50) {
      t.eval(x, df0, f, df);
      x = mma.step(x, df0, f, df);
      path.push_back(x[0]);
    }
    const auto& ref = by_hand[c++];
    ASSERT_EQ(path.size(), ref.size()) << g;
    // The subproblem's interior point stops at its relaxation epsimin = 1e-7: a binding bound is
    // then missed by about epsimin / |F′|, F the subproblem's objective — 1e-5 for g = −1e-2,
    // 1e-3 for g = −1e-4 (measured 2.7e-3 short of x = 1 in the last step; lsmbs scales its
    // objective to f/|f(p0)| and its variables to [0, 1], which keeps gradients far above that).
    const double tol = g == -1e-2 ? 1e-3 : 4e-3;
    for (size_t k = 0; k < ref.size(); ++k)
      EXPECT_NEAR(path[k], ref[k], tol) << g << ", iteration " << k + 1;
  }
}
