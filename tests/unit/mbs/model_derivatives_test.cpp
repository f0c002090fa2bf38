// The model's analytic derivatives against central finite differences of its own residual
// and constraints, on a case that contains every joint and force type (rigid bodies with
// centre-of-mass offsets, a flexible body, revolute joints body–body / body–ground /
// node–body, prismatic, rigid connection, clamp, absolute / relative rotation drivers, a
// translation driver, point masses on nodes and bodies, point forces, spring–dampers,
// pressure vs a body angle, gravity), at a random state off the constraint manifold.
#include <gtest/gtest.h>

#include <random>

#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

json every_element_case() {
  return R"({
  "name": "every_element",
  "gravity": [0.3, -9.81],
  "bodies": [
    {"name": "crank", "type": "rigid", "position": [0, 0], "angle": 0.3, "mass": 1.2, "inertia": 0.01, "com": [0.02, 0.01]},
    {"name": "link", "type": "rigid", "position": [0.1, 0.05], "angle": -0.2, "mass": 0.8, "inertia": 0.004, "com": [0.05, -0.005]},
    {"name": "slider", "type": "rigid", "position": [0.3, 0], "mass": 0.5, "inertia": 0.001},
    {"name": "floater", "type": "rigid", "position": [0, 0.5], "angle": 0.1, "mass": 1, "inertia": 0.01},
    {"name": "plate", "type": "flexible",
     "mesh": {"type": "rectangle", "origin": [0, -0.01], "size": [0.1, 0.02], "elements": [4, 2]},
     "placement": {"origin": [0.3, 0.1], "angle": 0.4},
     "material": {"E": 1e7, "nu": 0.3, "rho": 1000}, "thickness": 0.005},
    {"name": "rod", "type": "rigid", "position": [0.3, 0.1], "angle": 0.4, "mass": 0, "inertia": 0}
  ],
  "joints": [
    {"name": "j_ground", "type": "revolute", "a": {"body": "crank", "at": [0, 0]}, "b": "ground"},
    {"name": "j_crank_link", "type": "revolute", "a": {"body": "crank", "at": [0.1, 0]}, "b": {"body": "link", "at": [0, 0]}},
    {"name": "j_link_slider", "type": "revolute", "a": {"body": "link", "at": [0.2, 0.01]}, "b": {"body": "slider", "at": [0.01, 0]}},
    {"name": "slide", "type": "prismatic", "a": {"body": "slider", "at": [0.02, 0.01]}, "direction": [1, 0.2]},
    {"name": "slide_free", "type": "prismatic", "a": {"body": "floater", "at": [0.01, 0.0]}, "direction": [0.3, 1], "lock_rotation": false},
    {"name": "drive_crank", "type": "rotation_driver", "body": "crank", "law": {"type": "ramp", "from": 0.3, "speed": 40, "ramp_time": 0.2}},
    {"name": "drive_rel", "type": "rotation_driver", "body": "link", "relative_to": "crank",
     "law": {"type": "trapezoid", "from": -0.5, "to": 0.5, "acceleration": 3, "speed": 1}},
    {"name": "push", "type": "translation_driver", "point": {"body": "floater", "at": [0.01, 0.02]}, "direction": [0.6, 0.8],
     "law": {"type": "trapezoid", "from": 0, "to": 0.1, "acceleration": 2, "speed": 0.5}},
    {"name": "weld", "type": "rigid_connection", "rigid": "rod", "flexible": "plate", "node_set": "left"},
    {"name": "pin_node", "type": "revolute", "a": {"body": "plate", "nearest": [0.1, 0.01]}, "b": {"body": "link", "at": [0.1, 0]}},
    {"name": "fix_corner", "type": "clamp", "flexible": "plate", "node_set": "bottom"}
  ],
  "forces": [
    {"name": "m_node", "type": "point_mass", "mass": 0.2, "point": {"body": "plate", "nearest": [0.05, 0]}},
    {"name": "m_body", "type": "point_mass", "mass": 0.3, "point": {"body": "link", "at": [0.03, 0.01]}},
    {"name": "f_body", "type": "point_force", "point": {"body": "crank", "at": [0.05, 0.01]}, "force": [3, -2]},
    {"name": "f_node", "type": "point_force", "point": {"body": "plate", "node": 3},
     "fx": {"type": "table", "points": [[0, 0], [0.5, 2], [1, -1]]}, "fy": {"type": "constant", "value": 0.5}},
    {"name": "spring_body_node", "type": "spring_damper", "a": {"body": "crank", "at": [0.02, 0]}, "b": {"body": "plate", "nearest": [0, 0]},
     "stiffness": 1e3, "damping": 5, "free_length": 0.05},
    {"name": "spring_bodies", "type": "spring_damper", "a": {"body": "floater", "at": [0.0, 0.01]}, "b": {"body": "link", "at": [0.05, 0.0]},
     "stiffness": 500, "damping": 2},
    {"name": "gas", "type": "pressure", "point": {"body": "slider", "at": [0.01, 0]}, "direction": [-1, 0], "area": 1e-3,
     "table": {"points": [[0, 1e5], [1, 3e5], [2.5, 2e5], [4, 1e5]], "period": 4}, "argument": {"angle_of": "crank", "offset": 0.1}}
  ],
  "simulation": {"t_end": 1, "h": 0.01}
})"_json;
}

struct Fixture : ::testing::Test {
  Case cs = test::make_case(every_element_case());
  const Model& m = *cs.model;
  State s;
  double k = 7.0e2, zeta = 3.0e2;
  void SetUp() override {
    std::mt19937 g(42);
    std::uniform_real_distribution<double> u(-1, 1);
    s.t = 0.137;
    s.q = cs.initial.q;
    for (int i = 0; i < m.nq(); ++i) s.q[i] += 2e-3 * u(g);
    s.v = Vec::NullaryExpr(m.nq(), [&] { return u(g); });
    s.a = Vec::NullaryExpr(m.nq(), [&] { return 10 * u(g); });
    s.lambda = Vec::NullaryExpr(m.nc(), [&] { return u(g); });
  }
  Vec R(const State& x) const {
    Vec r;
    m.residual(x, m.params(), k, zeta, r);
    return r;
  }
  // d R / d (component) by central differences.
  Mat fd(Vec State::*member, double h) const {
    const int n = static_cast<int>((s.*member).size());
    Mat D(m.n(), n);
    for (int j = 0; j < n; ++j) {
      State p = s, q = s;
      (p.*member)[j] += h;
      (q.*member)[j] -= h;
      D.col(j) = (R(p) - R(q)) / (2 * h);
    }
    return D;
  }
  static void expect_close(const Mat& a, const Mat& ref, double rel, const Model& m, const char* what) {
    const double floor = 1e-9 * ref.lpNorm<Eigen::Infinity>();
    int bad = 0;
    for (int j = 0; j < ref.cols(); ++j)
      for (int i = 0; i < ref.rows(); ++i)
        if (std::abs(a(i, j) - ref(i, j)) > rel * std::abs(ref(i, j)) + floor && bad++ < 5)
          ADD_FAILURE() << what << " entry (" << i << ", " << j << ") [" << m.describe_unknown(i) << " / "
                        << m.describe_unknown(j) << "]: analytic " << a(i, j) << ", finite differences " << ref(i, j);
    EXPECT_EQ(bad, 0) << what;
  }
};

}  // namespace

TEST_F(Fixture, ModelContainsEveryElementType) {
  EXPECT_EQ(m.rigid_bodies().size(), 5u);
  EXPECT_EQ(m.flexible_bodies().size(), 1u);
  EXPECT_GT(m.nc(), 20);
}

TEST_F(Fixture, ConstraintJacobianMatchesCentralDifferences) {
  const Mat J = Mat(m.constraint_jacobian(s.t, s.q, m.params()));
  Mat D(m.nc(), m.nq());
  const double h = 1e-6;
  for (int j = 0; j < m.nq(); ++j) {
    Vec qp = s.q, qm = s.q, pp, pm;
    qp[j] += h;
    qm[j] -= h;
    m.constraints(s.t, qp, m.params(), pp);
    m.constraints(s.t, qm, m.params(), pm);
    D.col(j) = (pp - pm) / (2 * h);
  }
  expect_close(J, D, 1e-7, m, "Φ_q");
}

TEST_F(Fixture, StiffnessBlockAndConstraintBlocksMatchDifferencesOfTheResidual) {
  // S(0, 0, 1) = [K_t  kΦ_qᵀ ; kΦ_q 0]: columns of q by differences in q, columns of λ in λ.
  const Mat S = test::dense_iteration_matrix(m, s, {0, 0, 1}, k, zeta);
  Mat D(m.n(), m.n());
  D.leftCols(m.nq()) = fd(&State::q, 1e-7);
  D.rightCols(m.nc()) = fd(&State::lambda, 1e-4);
  expect_close(S, D, 1e-6, m, "[K_t kΦ_qᵀ; kΦ_q 0]");
}

TEST_F(Fixture, MassAndDampingBlocksMatchDifferencesOfTheResidual) {
  const Mat S0 = test::dense_iteration_matrix(m, s, {0, 0, 0}, k, zeta);
  const Mat M = (test::dense_iteration_matrix(m, s, {1, 0, 0}, k, zeta) - S0).topLeftCorner(m.nq(), m.nq());
  const Mat C = (test::dense_iteration_matrix(m, s, {0, 1, 0}, k, zeta) - S0).topLeftCorner(m.nq(), m.nq());
  expect_close(M, fd(&State::a, 1e-3).topRows(m.nq()), 1e-7, m, "M");
  expect_close(C, fd(&State::v, 1e-5).topRows(m.nq()), 1e-6, m, "C_t");
}

TEST_F(Fixture, IterationMatrixIsTheLinearCombinationOfEq20) {
  // S(c_a, c_v, c_q) must equal c_a M + c_v C + c_q K plus the constraint blocks.
  const double ca = 3.7e4, cv = 2.1e2, cq = 1.0;
  const Mat S0 = test::dense_iteration_matrix(m, s, {0, 0, 0}, k, zeta);
  const Mat Sm = test::dense_iteration_matrix(m, s, {1, 0, 0}, k, zeta) - S0;
  const Mat Sc = test::dense_iteration_matrix(m, s, {0, 1, 0}, k, zeta) - S0;
  const Mat Sk = test::dense_iteration_matrix(m, s, {0, 0, 1}, k, zeta);
  const Mat S = test::dense_iteration_matrix(m, s, {ca, cv, cq}, k, zeta);
  EXPECT_LT(test::rel_diff(S, ca * Sm + cv * Sc + Sk), 1e-13);
}

TEST_F(Fixture, VelocityAndAccelerationLevelConstraintTermsMatchDifferences) {
  // Along q(τ) = q + τ q̇ (q̈ = 0): dΦ/dτ = Φ_q q̇ + Φ_t and d²Φ/dτ² = γ.
  Vec phi_t, gamma;
  m.constraint_time_terms(s.t, s.q, s.v, m.params(), phi_t, gamma);
  auto phi_at = [&](double tau) {
    Vec p;
    m.constraints(s.t + tau, s.q + tau * s.v, m.params(), p);
    return p;
  };
  const double h = 1e-4;
  const Vec d1 = (phi_at(h) - phi_at(-h)) / (2 * h);
  const Vec d2 = (phi_at(h) - 2 * phi_at(0) + phi_at(-h)) / (h * h);
  const Mat J = Mat(m.constraint_jacobian(s.t, s.q, m.params()));
  const Vec vel = J * s.v + phi_t;
  EXPECT_LT((vel - d1).lpNorm<Eigen::Infinity>(), 1e-7 * std::max(1.0, d1.lpNorm<Eigen::Infinity>()));
  EXPECT_LT((gamma - d2).lpNorm<Eigen::Infinity>(), 1e-5 * std::max(1.0, d2.lpNorm<Eigen::Infinity>()));
}

TEST_F(Fixture, KineticEnergyIsHalfVtMv) {
  const Mat M = (test::dense_iteration_matrix(m, s, {1, 0, 0}, k, zeta) -
                 test::dense_iteration_matrix(m, s, {0, 0, 0}, k, zeta)).topLeftCorner(m.nq(), m.nq());
  EXPECT_NEAR(m.kinetic_energy(s, m.params()), 0.5 * s.v.dot(M * s.v), 1e-12 * s.v.dot(M * s.v));
}

TEST_F(Fixture, MassRateProductIsTheDerivativeOfMAlongTheMotion) {
  // Ṁ w = d/dτ [M(q + τ q̇) w] at τ = 0 (the adjoint's d/dt(Mᵀξ), idas_ggl.cpp): central
  // differences of the mass block along q̇; offset centres of mass make M depend on θ.
  std::mt19937 g(7);
  std::uniform_real_distribution<double> u(-1, 1);
  const Vec w = Vec::NullaryExpr(m.nq(), [&] { return u(g); });
  Vec out;
  m.mass_rate_product(s, m.params(), w, out);
  auto mass_times_w = [&](double tau) {
    State x = s;
    x.q += tau * s.v;
    const Mat M = (test::dense_iteration_matrix(m, x, {1, 0, 0}, k, zeta) -
                   test::dense_iteration_matrix(m, x, {0, 0, 0}, k, zeta)).topLeftCorner(m.nq(), m.nq());
    return Vec(M * w);
  };
  const double h = 1e-5;
  const Vec ref = (mass_times_w(h) - mass_times_w(-h)) / (2 * h);
  ASSERT_GT(ref.lpNorm<Eigen::Infinity>(), 1e-3) << "the case must have a mass matrix that depends on q";
  EXPECT_LT((out - ref).lpNorm<Eigen::Infinity>(), 1e-7 * ref.lpNorm<Eigen::Infinity>());
}
