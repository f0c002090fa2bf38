// Small free oscillation of a clamped plate started in its first mode: the frequency read from
// the time response (zero crossings, ρ∞ = 1, h = T₁/200) is within 1 % of the first
// generalized eigenvalue of the same model's K and M (dense solve: tiny model).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>

#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {
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

TEST(CantileverFrequency, FirstFrequencyFromTheTimeResponseMatchesTheEigenvalue) {
  const int nx = 30, ny = 4;
  json j = {{"name", "cantilever"},
            {"bodies", {{{"name", "beam"}, {"type", "flexible"},
                         {"mesh", {{"type", "rectangle"}, {"origin", {0, -0.025}}, {"size", {0.6, 0.05}}, {"elements", {nx, ny}}}},
                         {"material", {{"E", 72e9}, {"nu", 0.3}, {"rho", 2700}}}, {"thickness", 0.0025}}}},
            {"joints", {{{"type", "clamp"}, {"flexible", "beam"}, {"node_set", "left"}}}},
            {"simulation", {{"t_end", 1}, {"h", 1}}}};
  Case cs = test::make_case(j);
  const Model& m = *cs.model;
  State s0 = cs.initial;
  const Mat K = test::dense_iteration_matrix(m, s0, {0, 0, 1}, 1, 0).topLeftCorner(m.nq(), m.nq());
  const Mat M = (test::dense_iteration_matrix(m, s0, {1, 0, 0}, 1, 0) - test::dense_iteration_matrix(m, s0, {0, 0, 0}, 1, 0))
                    .topLeftCorner(m.nq(), m.nq());
  // free DOFs: all but the clamped nodes
  const auto& fb = *m.flexible_bodies()[0];
  std::vector<char> fixed(m.nq(), 0);
  for (int n : fb.mesh.node_sets.at("left")) fixed[2 * n] = fixed[2 * n + 1] = 1;
  std::vector<int> fr;
  for (int i = 0; i < m.nq(); ++i)
    if (!fixed[i]) fr.push_back(i);
  const int nf = static_cast<int>(fr.size());
  Mat Kf(nf, nf), Mf(nf, nf);
  for (int a = 0; a < nf; ++a)
    for (int b = 0; b < nf; ++b) Kf(a, b) = K(fr[a], fr[b]), Mf(a, b) = M(fr[a], fr[b]);
  Eigen::GeneralizedSelfAdjointEigenSolver<Mat> es(Kf, Mf);
  const double w1 = std::sqrt(es.eigenvalues()[0]);
  const double T1 = 2 * M_PI / w1;
  // start in mode 1 with a small velocity (tip speed 1e-4 m/s × ω₁ ...): linear regime
  Vec mode = Vec::Zero(m.nq());
  for (int a = 0; a < nf; ++a) mode[fr[a]] = es.eigenvectors()(a, 0);
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
  std::printf("eigenvalue: f1 = %.4f Hz; time response: f1 = %.4f Hz (%+.4f %%)\n", w1 / (2 * M_PI), 1 / period,
              100 * (T1 / period - 1));
  EXPECT_NEAR(T1 / period, 1.0, 0.01);
}
