// Aggregation of a measure over a time window (responses/aggregation.hpp): every kind against
// closed forms on the signals f_n(p) = p1 sin(t_n) + p2 t_n² sampled on a uniform grid, values
// and gradients (G row n = df_n/dp = (sin t_n, t_n²)), and the one implementation used by the
// simulate path (no derivatives) giving the same values as the sensitivity path.
#include "lsmbs/responses/aggregation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace lsmbs;
using K = ResponseSpec::Kind;

namespace {

constexpr double kPi = std::numbers::pi;

struct Signal {
  std::vector<double> t, v;
  Mat G;
};

// t_k = k h, k = 0..N; f = p1 sin t + p2 t²
Signal sample(double h, int N, double p1, double p2) {
  Signal s;
  s.G.resize(N + 1, 2);
  for (int k = 0; k <= N; ++k) {
    const double t = k * h;
    s.t.push_back(t);
    s.v.push_back(p1 * std::sin(t) + p2 * t * t);
    s.G(k, 0) = std::sin(t);
    s.G(k, 1) = t * t;
  }
  return s;
}

ResponseSpec spec(K kind, double t0 = -1e300, double t1 = 1e300, double ks = 0) {
  ResponseSpec r;
  r.kind = kind;
  r.t0 = t0;
  r.t1 = t1;
  r.ks = ks;
  return r;
}

// Σ_{k=a}^{b} sin(kh) = sin((b−a+1)h/2) sin((a+b)h/2) / sin(h/2)
double sum_sin(int a, int b, double h) {
  return std::sin((b - a + 1) * h / 2) * std::sin((a + b) * h / 2) / std::sin(h / 2);
}
// Σ_{k=a}^{b} (kh)² from Σ_{k=0}^{n} k² = n(n+1)(2n+1)/6
double sum_t2(int a, int b, double h) {
  auto S = [](double n) { return n * (n + 1) * (2 * n + 1) / 6; };
  return h * h * (S(b) - S(a - 1));
}

// Round-off of sums of O(1) terms over ≤ 1000 steps: a few hundred ulps of the result.
constexpr double kSumTol = 1e-13;

}  // namespace

TEST(Aggregation, AverageAndAverageEq45OverAWindowMatchClosedFormSums) {
  // window [0.3, 1.2] on h = 0.01: steps a = 30 … b = 120, n = 91 (both ends included, eq. 45's
  // n_cvi … n_cvf); average divides by n, average_eq45 by n_cvf − n_cvi = n − 1 as printed
  const double h = 0.01, p1 = 0.7, p2 = -1.3;
  const Signal s = sample(h, 200, p1, p2);
  const int a = 30, b = 120, n = b - a + 1;
  const double S1 = sum_sin(a, b, h), S2 = sum_t2(a, b, h);
  for (const K kind : {K::kAverage, K::kAverageEq45}) {
    const double div = kind == K::kAverage ? n : n - 1;
    const Aggregate g = aggregate(spec(kind, 0.3, 1.2), s.t, s.v, &s.G);
    ASSERT_EQ(g.count, n);
    ASSERT_EQ(g.values.size(), 1u);
    EXPECT_NEAR(g.values[0], (p1 * S1 + p2 * S2) / div, kSumTol) << ResponseSpec::kind_name(kind);
    EXPECT_NEAR(g.gradient(0, 0), S1 / div, kSumTol);
    EXPECT_NEAR(g.gradient(0, 1), S2 / div, kSumTol);
  }
  // the two differ by exactly n/(n − 1)
  const double avg = aggregate(spec(K::kAverage, 0.3, 1.2), s.t, s.v).scalar();
  const double eq45 = aggregate(spec(K::kAverageEq45, 0.3, 1.2), s.t, s.v).scalar();
  EXPECT_NEAR(eq45 / avg, double(n) / (n - 1), 1e-14);
  // eq. (45) is undefined for a window of one step
  EXPECT_TRUE(std::isnan(aggregate(spec(K::kAverageEq45, 0.5, 0.5), s.t, s.v).scalar()));
  EXPECT_DOUBLE_EQ(aggregate(spec(K::kAverage, 0.5, 0.5), s.t, s.v).scalar(),
                   p1 * std::sin(0.5) + p2 * 0.25);
}

TEST(Aggregation, TrapezoidalIntegralMatchesItsClosedFormOnSinAndTSquared) {
  // On [0, π] with N intervals the trapezoidal rule gives h cot(h/2) for sin (ends are zero),
  // and ∫t² + (b − a) h²/6 for t² (its error term (b − a) h² f''/12 is exact for a quadratic).
  const int N = 100;
  const double h = kPi / N, p1 = 2.0, p2 = 0.5;
  const Signal s = sample(h, N, p1, p2);
  const double I_sin = h / std::tan(h / 2), I_t2 = std::pow(kPi, 3) / 3 + kPi * h * h / 6;
  const Aggregate g = aggregate(spec(K::kIntegral), s.t, s.v, &s.G);
  EXPECT_NEAR(g.values[0], p1 * I_sin + p2 * I_t2, kSumTol * 10);
  EXPECT_NEAR(g.gradient(0, 0), I_sin, kSumTol);
  EXPECT_NEAR(g.gradient(0, 1), I_t2, kSumTol * 10);
  // and it converges to the integrals at second order: I_sin = 2 − h²/6 + O(h⁴)
  EXPECT_NEAR(I_sin, 2 - h * h / 6, h * h * h * h);
}

TEST(Aggregation, RmsOverAFullPeriodAndItsGradient) {
  // sin over one period, N steps, t_N = 2π: Σ_{k=0}^{N} sin² = N/2, so rms = sqrt(N / (2(N + 1)))
  // for p1 = 1, p2 = 0; d rms/dp = Σ f_n G_n / (n rms).
  const int N = 64;
  const double h = 2 * kPi / N;
  const Signal s = sample(h, N, 1.0, 0.0);
  const Aggregate g = aggregate(spec(K::kRms), s.t, s.v, &s.G);
  const double rms = std::sqrt(N / (2.0 * (N + 1)));
  EXPECT_NEAR(g.values[0], rms, 1e-15);
  // p1: rms is homogeneous of degree 1 in p1 when p2 = 0, so d rms/dp1 = rms / p1
  EXPECT_NEAR(g.gradient(0, 0), rms, 1e-15);
  // p2: Σ sin(t_k) t_k² / (n rms) with Σ_{k} k² sin(kh) in closed form by central differences of
  // rms(p2) instead (an independent evaluation of the same function)
  const double d = 1e-6;
  auto rms_at = [&](double p2) {
    const Signal x = sample(h, N, 1.0, p2);
    return aggregate(spec(K::kRms), x.t, x.v).scalar();
  };
  // truncation d²/6 |rms'''(p2)| with rms''' ~ (Σ G²/n)^{3/2} / rms² ~ 1e3 here: ~2e-10; round-off
  // ε rms / d ~ 1e-10 (measured difference 2.2e-9 on a gradient of −8.8: 2.5e-10 relative)
  EXPECT_NEAR(g.gradient(0, 1), (rms_at(d) - rms_at(-d)) / (2 * d), 1e-8);
}

TEST(Aggregation, MaxAndMinTakeTheExtremeStepAndItsDerivative) {
  // sin on [0, 2π] sampled with h = π/50: max 1 at t = π/2 (k = 25), min −1 at t = 3π/2 (k = 75)
  const double h = kPi / 50;
  const Signal s = sample(h, 100, 1.0, 0.0);
  const Aggregate mx = aggregate(spec(K::kMax), s.t, s.v, &s.G),
                  mn = aggregate(spec(K::kMin), s.t, s.v, &s.G);
  EXPECT_NEAR(mx.values[0], 1.0, 1e-15);
  EXPECT_NEAR(mn.values[0], -1.0, 1e-15);
  // d max/dp = G at the extreme step: (sin t*, t*²)
  EXPECT_NEAR(mx.gradient(0, 0), 1.0, 1e-15);
  EXPECT_NEAR(mx.gradient(0, 1), std::pow(kPi / 2, 2), 1e-13);
  EXPECT_NEAR(mn.gradient(0, 0), -1.0, 1e-15);
  EXPECT_NEAR(mn.gradient(0, 1), std::pow(3 * kPi / 2, 2), 1e-12);
  // within a window the extreme is the window's: sin on [2, 3] falls, so max at t = 2 and min at
  // t = 3 (grid steps 2/h and 3/h are not integers: the first step ≥ 2 and the last ≤ 3)
  const Aggregate w = aggregate(spec(K::kMin, 2.0, 3.0), s.t, s.v, &s.G);
  const int k3 = static_cast<int>(std::floor(3.0 / h));
  EXPECT_EQ(w.values[0], s.v[k3]);
  EXPECT_EQ(w.gradient(0, 1), s.G(k3, 1));
  EXPECT_EQ(aggregate(spec(K::kFinal, 2.0, 3.0), s.t, s.v, &s.G).values[0], s.v[k3]);
}

TEST(Aggregation, KreisselmeierSteinhauserBoundsAndGradient) {
  // n equal values c: KS = c + ln(n)/ks exactly; for any signal max ≤ KS ≤ max + ln(n)/ks;
  // the gradient is the softmax-weighted average of the rows of G (checked against central
  // differences of KS as a function of p).
  const std::vector<double> t = {0, 1, 2, 3, 4};
  const std::vector<double> c(5, 0.25);
  EXPECT_NEAR(aggregate(spec(K::kKS, -1e300, 1e300, 40), t, c).scalar(), 0.25 + std::log(5.0) / 40,
              1e-15);
  const double h = 0.05, ks = 20;
  const Signal s = sample(h, 80, 1.0, 0.2);
  const Aggregate g = aggregate(spec(K::kKS, -1e300, 1e300, ks), s.t, s.v, &s.G);
  const double mx = aggregate(spec(K::kMax), s.t, s.v).scalar();
  EXPECT_GE(g.values[0], mx);
  EXPECT_LE(g.values[0], mx + std::log(81.0) / ks);
  const double d = 1e-6;
  for (int i = 0; i < 2; ++i) {
    auto ks_at = [&](double e) {
      const Signal x = sample(h, 80, 1.0 + (i == 0 ? e : 0), 0.2 + (i == 1 ? e : 0));
      return aggregate(spec(K::kKS, -1e300, 1e300, ks), x.t, x.v).scalar();
    };
    EXPECT_NEAR(g.gradient(0, i), (ks_at(d) - ks_at(-d)) / (2 * d), 1e-8) << "p" << i + 1;
  }
}

TEST(Aggregation, PerStepGivesEveryStepOfTheWindowWithItsRow) {
  const double h = 0.1;
  const Signal s = sample(h, 30, 0.4, 0.9);
  const Aggregate g = aggregate(spec(K::kPerStep, 1.0, 2.0), s.t, s.v, &s.G);
  ASSERT_EQ(g.values.size(), 11u);  // t = 1.0, 1.1, …, 2.0 (ends within 1e-9 h)
  ASSERT_EQ(g.gradient.rows(), 11);
  for (int k = 0; k < 11; ++k) {
    const double t = (10 + k) * h;
    EXPECT_NEAR(g.times[k], t, 1e-15);
    EXPECT_NEAR(g.values[k], 0.4 * std::sin(t) + 0.9 * t * t, 1e-15);
    EXPECT_NEAR(g.gradient(k, 0), std::sin(t), 1e-15);
    EXPECT_NEAR(g.gradient(k, 1), t * t, 1e-15);
  }
  // the simulate path reports a per-step response by its largest value (t² dominates: the last)
  EXPECT_EQ(aggregate(spec(K::kPerStep, 1.0, 2.0), s.t, s.v).scalar(), g.values.back());
}

TEST(Aggregation, ValuesWithoutDerivativesAreTheValuesWithDerivatives) {
  // One implementation: the simulate path (no G) and the sensitivity path give bit-identical
  // values.
  const Signal s = sample(0.02, 150, -0.6, 0.35);
  for (const K kind : {K::kAverage, K::kAverageEq45, K::kMax, K::kMin, K::kFinal, K::kIntegral,
                       K::kRms, K::kPerStep, K::kKS}) {
    const ResponseSpec r = spec(kind, 0.5, 2.5, 30);
    const Aggregate a = aggregate(r, s.t, s.v), b = aggregate(r, s.t, s.v, &s.G);
    EXPECT_EQ(a.values, b.values) << ResponseSpec::kind_name(kind);
    EXPECT_EQ(a.count, b.count);
    EXPECT_EQ(a.gradient.cols(), 0);
    EXPECT_EQ(b.gradient.cols(), 2);
  }
  // an empty window has no value
  const Aggregate e = aggregate(spec(K::kAverage, 10, 11), s.t, s.v, &s.G);
  EXPECT_EQ(e.count, 0);
  EXPECT_TRUE(std::isnan(e.scalar()));
}
