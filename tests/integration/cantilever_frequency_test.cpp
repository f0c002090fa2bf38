// First bending frequency of a clamped plate 0.6 × 0.05 m, 2.5 mm thick (aluminium, plane
// stress) against Timoshenko beam theory (shear and rotary inertia; κ = 5/6), whose frequency
// equation is solved here by shooting: RK4 from the clamped end, bisection on ω for the
// determinant of the free-end conditions. The model's eigenvalue (inverse iteration on its K and
// M) and the frequency read from a free vibration started in that mode (zero crossings of the
// tip, ρ∞ = 1, h = T₁/200) are both compared with it; the time response's period also carries
// the trapezoidal rule's period elongation, a closed form of the scheme.
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <cmath>
#include <cstdio>

#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

constexpr double L = 0.6, H = 0.05, T = 0.0025, E = 72e9, NU = 0.3, RHO = 2700, KAPPA = 5.0 / 6.0;

// Timoshenko beam, clamped at x = 0, free at x = L:
//   κGA (w″ − ψ′) + ρA ω² w = 0,  EI ψ″ + κGA (w′ − ψ) + ρI ω² ψ = 0,
//   w = ψ = 0 at x = 0;  EI ψ′ = κGA (w′ − ψ) = 0 at x = L.
// The two solutions with (w′, ψ′)(0) = (1, 0) and (0, 1) must combine to satisfy both free-end
// conditions: det = 0. RK4 with 4000 steps resolves the mode shapes to ~1e-12.
double timoshenko_free_end_determinant(double w) {
  const double A = T * H, I = T * H * H * H / 12, kGA = KAPPA * E / (2 * (1 + NU)) * A, EI = E * I;
  using V4 = Eigen::Vector4d;  // (w, w′, ψ, ψ′)
  auto f = [&](const V4& y) {
    return V4(y[1], y[3] - RHO * A * w * w * y[0] / kGA, y[3],
              -(kGA * (y[1] - y[2]) + RHO * I * w * w * y[2]) / EI);
  };
  double c[2][2];
  for (int k = 0; k < 2; ++k) {
    V4 y = k == 0 ? V4(0, 1, 0, 0) : V4(0, 0, 0, 1);
    const int n = 4000;
    const double dx = L / n;
    for (int i = 0; i < n; ++i) {
      const V4 k1 = f(y), k2 = f(y + 0.5 * dx * k1), k3 = f(y + 0.5 * dx * k2), k4 = f(y + dx * k3);
      y += dx / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    c[k][0] = y[3];         // bending moment / EI
    c[k][1] = y[1] - y[2];  // shear / κGA
  }
  return c[0][0] * c[1][1] - c[1][0] * c[0][1];
}

// First root of the determinant, bracketed between 0.95 and 1 times the Euler–Bernoulli value
// (shear and rotary inertia only lower the frequency; the second mode is 6 times higher).
double timoshenko_omega1(double w_eb) {
  double lo = 0.95 * w_eb, hi = w_eb;
  const double dlo = timoshenko_free_end_determinant(lo);
  EXPECT_LT(dlo * timoshenko_free_end_determinant(hi), 0) << "root not bracketed";
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (timoshenko_free_end_determinant(mid) * dlo > 0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

struct TipRecorder : StepObserver {
  int dof;
  std::vector<double> t, y;
  bool on_step(const StepInfo& i) override {
    t.push_back(i.state->t);
    y.push_back(i.state->q[dof]);
    return true;
  }
};

}  // namespace

TEST(CantileverFrequency, FirstFrequencyMatchesTimoshenkoBeamTheory) {
  // Euler–Bernoulli: ω = (β₁L)² sqrt(EI / (ρA L⁴)), β₁L = 1.8751040687 (cos βL cosh βL = −1)
  const double w_eb = std::pow(1.8751040687, 2) * std::sqrt(E * H * H / (12 * RHO)) / (L * L);
  const double w_ref = timoshenko_omega1(w_eb);
  // Mesh 120 × 10 (5 mm, the robot arm's): its static tip deflection is 0.27 % stiffer than
  // Timoshenko's (CantileverStatic), so the frequency, ∝ sqrt(stiffness), about 0.14 % higher;
  // the clamped root (no Poisson contraction at x = 0) and the consistent mass add less than
  // 0.1 %. The 0.3 % asked for therefore holds with margin; 60 × 5 (0.6 % stiffer) would not.
  const int nx = 120, ny = 10;
  json j = {{"name", "cantilever"},
            {"bodies",
             {{{"name", "beam"},
               {"type", "flexible"},
               {"mesh",
                {{"type", "rectangle"},
                 {"origin", {0, -H / 2}},
                 {"size", {L, H}},
                 {"elements", {nx, ny}}}},
               {"material", {{"E", E}, {"nu", NU}, {"rho", RHO}}},
               {"thickness", T}}}},
            {"joints", {{{"type", "clamp"}, {"flexible", "beam"}, {"node_set", "left"}}}},
            {"simulation", {{"t_end", 1}, {"h", 1}}}};
  Case cs = test::make_case(j);
  const Model& m = *cs.model;
  // free DOFs: all but the clamped nodes
  const auto& fb = *m.flexible_bodies()[0];
  std::vector<int> index(m.nq(), 0);
  for (int n : fb.mesh.node_sets.at("left")) index[2 * n] = index[2 * n + 1] = -1;
  int nf = 0;
  for (int i = 0; i < m.nq(); ++i)
    if (index[i] >= 0) index[i] = nf++;
  auto free_block = [&](const SpMat& A) {
    std::vector<Eigen::Triplet<double>> t;
    for (int c = 0; c < A.outerSize(); ++c)
      for (SpMat::InnerIterator it(A, c); it; ++it)
        if (index[it.row()] >= 0 && index[it.col()] >= 0)
          t.emplace_back(index[it.row()], index[it.col()], it.value());
    SpMat B(nf, nf);
    B.setFromTriplets(t.begin(), t.end());
    return B;
  };
  const SpMat K = free_block(test::sparse_tangent_stiffness(m, cs.initial));
  const SpMat M = free_block(test::sparse_mass_matrix(m, cs.initial));
  // lowest mode by inverse iteration: the error falls by (ω₁/ω₂)² ≈ 1/39 per iteration
  Eigen::SimplicialLDLT<SpMat> K_inv(K);
  ASSERT_EQ(K_inv.info(), Eigen::Success);
  Vec x = Vec::Ones(nf), y;
  double w2 = 0;
  for (int it = 0; it < 30; ++it) {
    y = K_inv.solve(M * x);
    w2 = x.dot(M * x) / x.dot(M * y);  // Rayleigh quotient of y ≈ x / ω²
    x = y / std::sqrt(y.dot(M * y));
  }
  const double w1 = std::sqrt(w2), T1 = 2 * M_PI / w1;
  // start in mode 1 with a small velocity (tip speed 1e-5 ω₁ m/s): linear regime
  Vec mode = Vec::Zero(m.nq());
  for (int i = 0; i < m.nq(); ++i)
    if (index[i] >= 0) mode[i] = x[index[i]];
  const int tip = (ny / 2) * (nx + 1) + nx;
  mode *= 1e-5 * w1 / std::abs(mode[2 * tip + 1]);
  cs.initial.v = mode;
  cs.simulation.h = T1 / 200;
  cs.simulation.t_end = 3.2 * T1;
  cs.simulation.rho_inf = 1.0;
  cs.simulation.tol_r = 1e-12;
  TipRecorder rec;
  rec.dof = 2 * tip + 1;
  const double y0 = cs.initial.q[rec.dof];
  const auto sum = GeneralizedAlpha(cs.simulation).run(m, m.params(), cs.initial, {&rec});
  ASSERT_TRUE(sum.ok) << sum.message;
  std::vector<double> zc;  // upward zero crossings of the tip displacement
  for (size_t i = 1; i < rec.t.size(); ++i) {
    const double a = rec.y[i - 1] - y0, b = rec.y[i] - y0;
    if (a < 0 && b >= 0) zc.push_back(rec.t[i - 1] + (rec.t[i] - rec.t[i - 1]) * (-a) / (b - a));
  }
  ASSERT_GE(zc.size(), 3u);
  const double period = (zc.back() - zc.front()) / (zc.size() - 1);
  // trapezoidal rule (generalized-α with ρ∞ = 1 on a linear system): the discrete frequency is
  // (2/h) atan(ωh/2), a period elongation ωh / (2 atan(ωh/2)) − 1 ≈ (ωh)²/12
  const double wh = w1 * cs.simulation.h, elongation = wh / (2 * std::atan(wh / 2)) - 1;
  std::printf(
      "f1: Euler-Bernoulli %.4f Hz, Timoshenko %.4f Hz; model %dx%d: eigenvalue %.4f Hz (%+.3f "
      "%%), time "
      "response %.4f Hz (%+.3f %%); period elongation %.4e, closed form %.4e\n",
      w_eb / (2 * M_PI), w_ref / (2 * M_PI), nx, ny, w1 / (2 * M_PI), 100 * (w1 / w_ref - 1),
      1 / period, 100 * (2 * M_PI / period / w_ref - 1), period / T1 - 1, elongation);
  EXPECT_NEAR(w1 / w_ref, 1.0, 3e-3);
  EXPECT_NEAR(2 * M_PI / period / w_ref, 1.0, 3e-3);
  // what remains is the linear interpolation of the crossing times, at inflection points of the
  // sine (third order in ωh: ~1e-5 of a step, a few 1e-8 of the period): measured 1.1e-8
  EXPECT_NEAR(period / T1 - 1, elongation, 1e-7);
}
