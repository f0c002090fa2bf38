// The model's analytic derivatives against central finite differences of its own residual
// and constraints, on a case that contains every joint and force type (rigid bodies with
// centre-of-mass offsets, a flexible body, revolute joints body–body / body–ground /
// node–body, prismatic, rigid connection, clamp, absolute / relative rotation drivers, a
// translation driver, point masses on nodes and bodies, point forces, spring–dampers,
// pressure vs a body angle, torques, rotational spring–dampers body–body and body–ground,
// gravity), at a random state off the constraint manifold. The exact parameter derivatives
// ∂r/∂p (ForceElement::param_derivative) are checked against central differences of the
// residual for every scalar parameter, and against closed forms element by element.
#include <gtest/gtest.h>

#include <random>

#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

// Every element type at once, for derivative checks of the model's functions (never integrated:
// its constraints are redundant, hence "check_constraints": false).
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
    {"name": "rod", "type": "rigid", "position": [0.3, 0.1], "angle": 0.4, "mass": 0, "inertia": 0},
    {"name": "tri_plate", "type": "flexible",
     "mesh": {"type": "rectangle", "origin": [0, -0.01], "size": [0.08, 0.02], "elements": [3, 2], "cells": "tri3"},
     "placement": {"origin": [0.5, 0.2], "angle": -0.3},
     "material": {"E": 2e7, "nu": 0.25, "rho": 1200}, "thickness": 0.004}
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
    {"name": "spring_tri", "type": "spring_damper", "a": {"body": "slider", "at": [0.0, 0.01]}, "b": {"body": "tri_plate", "nearest": [0.08, 0.01]},
     "stiffness": 800, "damping": 3, "free_length": 0.1},
    {"name": "spring_bodies", "type": "spring_damper", "a": {"body": "floater", "at": [0.0, 0.01]}, "b": {"body": "link", "at": [0.05, 0.0]},
     "stiffness": 500, "damping": 2},
    {"name": "gas", "type": "pressure", "point": {"body": "slider", "at": [0.01, 0]}, "direction": [-1, 0], "area": 1e-3,
     "table": {"points": [[0, 1e5], [1, 3e5], [2.5, 2e5], [4, 1e5]], "period": 4}, "argument": {"angle_of": "crank", "offset": 0.1}},
    {"name": "motor", "type": "torque", "body": "crank", "scale": 1.5,
     "law": {"type": "table", "points": [[0, 0.5], [0.1, 2], [0.3, -1], [1, 0.2]]}},
    {"name": "brake", "type": "torque", "body": "floater", "torque": -0.7},
    {"name": "torsion_bodies", "type": "rotational_spring_damper", "a": "link", "b": "floater",
     "stiffness": 20, "damping": 0.3, "free_angle": 0.2},
    {"name": "torsion_ground", "type": "rotational_spring_damper", "a": "slider", "b": "ground", "stiffness": 5, "damping": 0.1}
  ],
  "simulation": {"t_end": 1, "h": 0.01, "check_constraints": false}
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
  static void expect_close(const Mat& a, const Mat& ref, double rel, const Model& m,
                           const char* what) {
    const double floor = 1e-9 * ref.lpNorm<Eigen::Infinity>();
    int bad = 0;
    for (int j = 0; j < ref.cols(); ++j)
      for (int i = 0; i < ref.rows(); ++i)
        if (std::abs(a(i, j) - ref(i, j)) > rel * std::abs(ref(i, j)) + floor && bad++ < 5)
          ADD_FAILURE() << what << " entry (" << i << ", " << j << ") [" << m.describe_unknown(i)
                        << " / " << m.describe_unknown(j) << "]: analytic " << a(i, j)
                        << ", finite differences " << ref(i, j);
    EXPECT_EQ(bad, 0) << what;
  }
};

}  // namespace

TEST_F(Fixture, ModelContainsEveryElementType) {
  EXPECT_EQ(m.rigid_bodies().size(), 5u);
  EXPECT_EQ(m.flexible_bodies().size(), 2u);  // quadrilaterals and triangles
  EXPECT_GT(m.nc(), 20);
  int torques = 0, rotational = 0;
  for (const auto& f : m.forces()) {
    torques += dynamic_cast<const Torque*>(f.get()) != nullptr;
    rotational += dynamic_cast<const RotationalSpringDamper*>(f.get()) != nullptr;
  }
  EXPECT_EQ(torques, 2);
  EXPECT_EQ(rotational, 2);
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
  const Mat M = test::dense_mass_matrix(m, s), C = test::dense_damping_matrix(m, s);
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
  EXPECT_LT((vel - d1).lpNorm<Eigen::Infinity>(),
            1e-7 * std::max(1.0, d1.lpNorm<Eigen::Infinity>()));
  EXPECT_LT((gamma - d2).lpNorm<Eigen::Infinity>(),
            1e-5 * std::max(1.0, d2.lpNorm<Eigen::Infinity>()));
}

namespace {

// ∂(Φ_q(q) x)/∂q and ∂(Φ_q(q)ᵀ w)/∂q by central differences of the analytic Φ_q (itself checked
// against differences of Φ above). Φ is at most quadratic in each position times sin/cos of the
// angles: with h = 1e-5 the truncation (h² × third derivatives ~ 1) and the round-off
// (ε ‖Φ_q‖ / h ~ 1e-11) both stay below 1e-9 of the entries.
Mat fd_of_jacobian(const Model& m, const State& s, const Vec& x, bool transposed) {
  const double h = 1e-5;
  const int rows = transposed ? m.nq() : m.nc();
  Mat D(rows, m.nq());
  for (int j = 0; j < m.nq(); ++j) {
    Vec qp = s.q, qm = s.q;
    qp[j] += h;
    qm[j] -= h;
    const SpMat Jp = m.constraint_jacobian(s.t, qp, m.params()),
                Jm = m.constraint_jacobian(s.t, qm, m.params());
    D.col(j) = transposed ? Vec((Jp.transpose() * x - Jm.transpose() * x) / (2 * h))
                          : Vec((Jp * x - Jm * x) / (2 * h));
  }
  return D;
}

}  // namespace

TEST_F(Fixture, ConstraintHessianIsTheDerivativeOfTheTransposedJacobianTimesW) {
  // Σ_i w_i ∂²Φ_i/∂q² = ∂(Φ_qᵀ w)/∂q, the geometric stiffness of the constraint forces
  std::mt19937 g(11);
  std::uniform_real_distribution<double> u(-1, 1);
  const Vec w = Vec::NullaryExpr(m.nc(), [&] { return u(g); });
  const SpMat H = m.constraint_hessian(s.t, s.q, w);
  ASSERT_EQ(H.rows(), m.nq());
  ASSERT_EQ(H.cols(), m.nq());
  const Mat ref = fd_of_jacobian(m, s, w, true);
  ASSERT_GT(ref.lpNorm<Eigen::Infinity>(), 1e-2)
      << "the case must have constraints non-linear in q";
  expect_close(Mat(H), ref, 1e-8, m, "Σ w_i ∂²Φ_i/∂q²");
  EXPECT_LT((Mat(H) - Mat(H).transpose()).lpNorm<Eigen::Infinity>(),
            1e-14 * ref.lpNorm<Eigen::Infinity>())
      << "a Hessian is symmetric";
  // the pattern holds explicit zeros: the same at w = 0 and at another state
  State x = s;
  x.q.array() += 0.01;
  EXPECT_EQ(m.constraint_hessian(s.t, s.q, Vec::Zero(m.nc())).nonZeros(), H.nonZeros());
  EXPECT_EQ(m.constraint_hessian(x.t, x.q, w).nonZeros(), H.nonZeros());
}

TEST_F(Fixture, VelocityConstraintJacobianIsTheDerivativeOfTheJacobianTimesTheVelocity) {
  // ∂(Φ_q q̇)/∂q, row i = (∂²Φ_i/∂q² q̇)ᵀ (the GGL index-2 system's Jacobian of IDAS)
  const SpMat V = m.velocity_constraint_jacobian(s.t, s.q, s.v);
  ASSERT_EQ(V.rows(), m.nc());
  ASSERT_EQ(V.cols(), m.nq());
  const Mat ref = fd_of_jacobian(m, s, s.v, false);
  ASSERT_GT(ref.lpNorm<Eigen::Infinity>(), 1e-2);
  expect_close(Mat(V), ref, 1e-8, m, "∂(Φ_q q̇)/∂q");
  // consistent with the Hessian: (∂(Φ_q q̇)/∂q)ᵀ w = Σ_i w_i ∂²Φ_i/∂q² q̇
  std::mt19937 g(12);
  std::uniform_real_distribution<double> u(-1, 1);
  const Vec w = Vec::NullaryExpr(m.nc(), [&] { return u(g); });
  const Vec a = V.transpose() * w, b = m.constraint_hessian(s.t, s.q, w) * s.v;
  EXPECT_LT((a - b).lpNorm<Eigen::Infinity>(), 1e-12 * b.lpNorm<Eigen::Infinity>());
  EXPECT_EQ(m.velocity_constraint_jacobian(s.t, s.q, Vec::Zero(m.nq())).nonZeros(), V.nonZeros());
}

TEST_F(Fixture, KineticEnergyEqualsTheClosedFormOfEveryBodyAndPointMass) {
  // T = Σ_rigid ½ m |v_G|² + ½ J_G ω² (v_G = ẋ + ω R′(θ) c of the centre of mass at offset c from
  // the reference point), + Σ_point masses ½ m |v_P|², + each plate's ½ ρ t ∫ |v(X)|² dA with v the
  // bilinear interpolation of the nodal velocities, integrated by 3 × 3 Gauss on each quad (exact:
  // |v|² det J is of degree ≤ 3 in each of ξ, η). Masses and offsets are those of the JSON above.
  double T = 0;
  auto point_velocity = [&](const std::string& body, const Vec2& d) {
    const int b = m.find_rigid(body)->dof0;
    return Vec2(s.v.segment<2>(b) + s.v[b + 2] * rotation_derivative(s.q[b + 2]) * d);
  };
  struct Rigid {
    const char* name;
    double mass, J;
    Vec2 c;
  };
  const Rigid rigid[] = {{"crank", 1.2, 0.01, {0.02, 0.01}},
                         {"link", 0.8, 0.004, {0.05, -0.005}},
                         {"slider", 0.5, 0.001, {0, 0}},
                         {"floater", 1, 0.01, {0, 0}},
                         {"rod", 0, 0, {0, 0}}};
  for (const auto& r : rigid)
    T += 0.5 * r.mass * point_velocity(r.name, r.c).squaredNorm() +
         0.5 * r.J * std::pow(s.v[m.find_rigid(r.name)->dof0 + 2], 2);
  T += 0.5 * 0.3 * point_velocity("link", {0.03, 0.01}).squaredNorm();  // m_body
  const FlexibleBody& plate = *m.find_flexible("plate");
  int node = 0;  // m_node: the node nearest to (0.05, 0) in the mesh frame
  for (int i = 0; i < plate.mesh.num_nodes(); ++i)
    if ((plate.mesh.nodes[i] - Vec2(0.05, 0)).norm() <
        (plate.mesh.nodes[node] - Vec2(0.05, 0)).norm())
      node = i;
  T += 0.5 * 0.2 * s.v.segment<2>(plate.node_dof(node)).squaredNorm();
  const double rho_t = 1000 * 0.005, g = std::sqrt(0.6), gp[3] = {-g, 0, g},
               gw[3] = {5.0 / 9, 8.0 / 9, 5.0 / 9};
  const double xi_n[4] = {-1, 1, 1, -1}, eta_n[4] = {-1, -1, 1, 1};  // counter-clockwise corners
  for (const auto& quad : plate.mesh.cells)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        Vec2 v = Vec2::Zero(), dX_dxi = Vec2::Zero(), dX_deta = Vec2::Zero();
        for (int I = 0; I < 4; ++I) {
          const double N = 0.25 * (1 + xi_n[I] * gp[a]) * (1 + eta_n[I] * gp[b]);
          v += N * s.v.segment<2>(plate.node_dof(quad[I]));
          dX_dxi += 0.25 * xi_n[I] * (1 + eta_n[I] * gp[b]) * plate.mesh.nodes[quad[I]];
          dX_deta += 0.25 * eta_n[I] * (1 + xi_n[I] * gp[a]) * plate.mesh.nodes[quad[I]];
        }
        const double detJ = dX_dxi.x() * dX_deta.y() - dX_dxi.y() * dX_deta.x();
        T += 0.5 * rho_t * gw[a] * gw[b] * detJ * v.squaredNorm();
      }
  // the triangle plate: v linear on each triangle, ∫ N_I N_J dA = A (1 + δ_IJ) / 12, so
  // ∫ |v|² dA = A/12 (Σ |v_I|² + |Σ v_I|²)
  const FlexibleBody& tri = *m.find_flexible("tri_plate");
  for (const auto& cell : tri.mesh.cells) {
    const Vec2 X0 = tri.mesh.nodes[cell[0]], d1 = tri.mesh.nodes[cell[1]] - X0,
               d2 = tri.mesh.nodes[cell[2]] - X0;
    const double A = 0.5 * std::abs(d1.x() * d2.y() - d1.y() * d2.x());
    Vec2 sum = Vec2::Zero();
    double sq = 0;
    for (int I = 0; I < 3; ++I) {
      const Vec2 v = s.v.segment<2>(tri.node_dof(cell[I]));
      sum += v, sq += v.squaredNorm();
    }
    T += 0.5 * 1200 * 0.004 * A / 12 * (sq + sum.squaredNorm());
  }
  const double Tm = m.kinetic_energy(s, m.params());
  std::printf("kinetic energy: model %.15e, closed form %.15e (%.1e)\n", Tm, T,
              std::abs(Tm / T - 1));
  // both sums are exact: round-off of a few dozen terms of one sign
  EXPECT_NEAR(Tm, T, 1e-13 * T);
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
    return Vec(test::dense_mass_matrix(m, x) * w);
  };
  const double h = 1e-5;
  const Vec ref = (mass_times_w(h) - mass_times_w(-h)) / (2 * h);
  ASSERT_GT(ref.lpNorm<Eigen::Infinity>(), 1e-3)
      << "the case must have a mass matrix that depends on q";
  EXPECT_LT((out - ref).lpNorm<Eigen::Infinity>(), 1e-7 * ref.lpNorm<Eigen::Infinity>());
}

// ---------------------------------------------------------------- ∂r/∂p of scalar parameters

namespace {

// ∂R/∂p_j from Model::residual_param_derivative (the exact element derivatives).
Vec exact_param_derivative(const Model& m, const State& s, int j) {
  ParamDirection d;
  d.scalars.emplace_back(j, 1.0);
  Vec out;
  m.residual_param_derivative(s, m.params(), d, out);
  return out;
}

// ∂R/∂p_j by central differences of the whole residual. Every scalar parameter but ν enters r
// linearly, so the difference is exact up to round-off ε‖R‖/h, and a large step (1 % of the
// value) keeps that small; ν is non-linear, hence Richardson extrapolation of two central
// differences (error O(h⁴)).
Vec fd_param_derivative(const Model& m, const State& s, int j, double k, double zeta) {
  ModelParams p = m.params();
  const double v0 = p.scalars[j], h = 1e-2 * std::max(std::abs(v0), 1e-3);
  auto R = [&](double v) {
    p.scalars[j] = v;
    Vec r;
    m.residual(s, p, k, zeta, r);
    return r;
  };
  const Vec d1 = (R(v0 + h) - R(v0 - h)) / (2 * h), d2 = (R(v0 + 2 * h) - R(v0 - 2 * h)) / (4 * h);
  return (4 * d1 - d2) / 3;
}

}  // namespace

TEST_F(Fixture, ParameterDerivativesMatchCentralDifferencesOfTheResidualForEveryScalarParameter) {
  double worst = 0, worst_linear = 0;
  std::string worst_name;
  const auto& names = m.parameter_names();
  for (int j = 0; j < static_cast<int>(names.size()); ++j) {
    const Vec a = exact_param_derivative(m, s, j), ref = fd_param_derivative(m, s, j, k, zeta);
    const double scale = ref.lpNorm<Eigen::Infinity>();
    ASSERT_GT(scale, 0) << names[j] << ": the parameter must act on the residual at this state";
    const double e = (a - ref).lpNorm<Eigen::Infinity>() / scale;
    EXPECT_LT(e, 1e-8) << names[j];
    EXPECT_EQ(a.tail(m.nc()).lpNorm<Eigen::Infinity>(), 0.0)
        << names[j] << ": constraints carry no parameter";
    if (e > worst) worst = e, worst_name = names[j];
    if (!names[j].ends_with(".nu")) worst_linear = std::max(worst_linear, e);
  }
  std::printf(
      "∂R/∂p exact vs central differences, %zu scalar parameters: worst relative error %.2e (%s); "
      "without ν %.2e\n",
      names.size(), worst, worst_name.c_str(), worst_linear);
}

TEST_F(Fixture, ParameterDerivativeAlongMaterialFieldsAndScalarsMatchesCentralDifferences) {
  // A direction that moves μ_e of every element of both plates (quadrilaterals, triangles) and
  // two scalar parameters at once:
  // ∂R/∂p·d against central differences of R along d. R is linear in each μ_e (eq. 3) and in
  // k, c of a spring, so the difference is exact up to round-off: ε ‖R‖ / h with h = 1e-3.
  std::mt19937 g(13);
  std::uniform_real_distribution<double> u(-1, 1);
  ParamDirection d;
  for (const char* plate : {"plate", "tri_plate"}) {
    const FlexibleBody& b = *m.find_flexible(plate);
    for (int e = 0; e < b.mesh.num_elements(); ++e) d.fields.push_back({b.field, e, u(g)});
  }
  d.scalars.emplace_back(m.parameter_index("spring_bodies.stiffness"), 300.0);
  d.scalars.emplace_back(m.parameter_index("spring_body_node.damping"), -2.0);
  Vec exact;
  m.residual_param_derivative(s, m.params(), d, exact);
  const double h = 1e-3;
  auto R_at = [&](double t) {
    ModelParams p = m.params();
    add_direction(p, d, t);
    Vec r;
    m.residual(s, p, k, zeta, r);
    return r;
  };
  const Vec ref = (R_at(h) - R_at(-h)) / (2 * h);
  ASSERT_GT(ref.lpNorm<Eigen::Infinity>(), 0);
  const double err = (exact - ref).lpNorm<Eigen::Infinity>() / ref.lpNorm<Eigen::Infinity>();
  std::printf("∂R/∂p along material fields and scalars vs central differences: %.2e\n", err);
  EXPECT_LT(err, 1e-9);
  EXPECT_EQ(exact.tail(m.nc()).lpNorm<Eigen::Infinity>(), 0.0);
}

TEST_F(Fixture, ParameterDerivativeOfEachElementMatchesDifferencesOfItsOwnResidual) {
  // Element by element (local vectors), for every parameter the element reads.
  double worst = 0;
  for (int e = 0; e < static_cast<int>(m.forces().size()); ++e) {
    const auto& f = *m.forces()[e];
    for (int j = 0; j < static_cast<int>(m.parameter_names().size()); ++j) {
      if (!f.uses_parameter(j)) continue;
      LocalState ls;
      ls.t = s.t;
      const auto d = f.dofs();
      const auto nd = static_cast<Eigen::Index>(d.size());
      ls.q.resize(nd), ls.v.resize(nd), ls.a.resize(nd);
      for (Eigen::Index i = 0; i < nd; ++i)
        ls.q[i] = s.q[d[i]], ls.v[i] = s.v[d[i]], ls.a[i] = s.a[d[i]];
      LocalVec dr = LocalVec::Zero(nd);
      f.param_derivative(ls, m.params(), j, dr);
      ModelParams p = m.params();
      const double v0 = p.scalars[j],
                   h = 1e-2 * std::max(std::abs(v0), 1e-3);  // as fd_param_derivative
      auto r_at = [&](double v) {
        p.scalars[j] = v;
        LocalVec r;
        m.element_residual(e, s, p, r);
        return r;
      };
      const LocalVec d1 = (r_at(v0 + h) - r_at(v0 - h)) / (2 * h),
                     d2 = (r_at(v0 + 2 * h) - r_at(v0 - 2 * h)) / (4 * h);
      const LocalVec ref = (4 * d1 - d2) / 3;
      const double scale = std::max(ref.lpNorm<Eigen::Infinity>(), 1e-300);
      const double err = (dr - ref).lpNorm<Eigen::Infinity>() / scale;
      EXPECT_LT(err, 1e-8) << f.describe() << ", parameter " << m.parameter_names()[j];
      worst = std::max(worst, err);
      // an element adds nothing for a parameter it does not read
      LocalVec none = LocalVec::Zero(nd);
      for (int other = 0; other < static_cast<int>(m.parameter_names().size()); ++other)
        if (!f.uses_parameter(other)) f.param_derivative(ls, m.params(), other, none);
      EXPECT_EQ(none.lpNorm<Eigen::Infinity>(), 0.0) << f.describe();
    }
  }
  std::printf("element ∂r_e/∂p vs central differences of r_e: worst relative error %.2e\n", worst);
}

namespace {

// The local state of force element e and its ∂r_e/∂p_j.
struct ElementAt {
  LocalState ls;
  LocalVec dr;
};
ElementAt element_derivative(const Model& m, const State& s, int e, const std::string& param) {
  const int j = m.parameter_index(param);
  EXPECT_GE(j, 0) << param;
  const auto& f = *m.forces()[e];
  ElementAt out;
  out.ls.t = s.t;
  const auto d = f.dofs();
  const auto nd = static_cast<Eigen::Index>(d.size());
  out.ls.q.resize(nd), out.ls.v.resize(nd), out.ls.a.resize(nd);
  for (Eigen::Index i = 0; i < nd; ++i)
    out.ls.q[i] = s.q[d[i]], out.ls.v[i] = s.v[d[i]], out.ls.a[i] = s.a[d[i]];
  out.dr = LocalVec::Zero(nd);
  f.param_derivative(out.ls, m.params(), j, out.dr);
  return out;
}
int force_index(const Model& m, const std::string& describe) {
  for (size_t e = 0; e < m.forces().size(); ++e)
    if (m.forces()[e]->describe() == describe) return static_cast<int>(e);
  ADD_FAILURE() << "no force '" << describe << "'";
  return 0;
}
double rel(const LocalVec& a, const LocalVec& b) {
  return (a - b).lpNorm<Eigen::Infinity>() / std::max(b.lpNorm<Eigen::Infinity>(), 1e-300);
}

}  // namespace

TEST_F(Fixture, SpringParameterDerivativesMatchTheClosedForm) {
  // Spring from a point of `floater` (A) to a point of `link` (B): d = p_B − p_A, l = |d|,
  // n = d/l, l̇ = n·ḋ. The force on B is F_B = −T n with T = k (l − l0) + c l̇, so
  // ∂F_B/∂k = −(l − l0) n and ∂F_B/∂c = −l̇ n; eq. (7) has r_B = −F_B on B's translation rows
  // and r_A = −F_A = −T n on A's; the angle rows carry the moments (R′(θ) d_local)·(∓T n).
  const int e = force_index(m, "spring 'spring_bodies'");
  const double k0 = m.params().scalars[m.parameter_index("spring_bodies.stiffness")];
  const double l0 = m.params().scalars[m.parameter_index("spring_bodies.free_length")];
  const RigidBody& A = *m.find_rigid("floater");
  const RigidBody& B = *m.find_rigid("link");
  const Vec2 da(0.0, 0.01), db(0.05, 0.0);
  const double tha = s.q[A.dof0 + 2], thb = s.q[B.dof0 + 2];
  const Vec2 pa = s.q.segment<2>(A.dof0) + rotation(tha) * da,
             pb = s.q.segment<2>(B.dof0) + rotation(thb) * db;
  const Vec2 va = s.v.segment<2>(A.dof0) + s.v[A.dof0 + 2] * rotation_derivative(tha) * da;
  const Vec2 vb = s.v.segment<2>(B.dof0) + s.v[B.dof0 + 2] * rotation_derivative(thb) * db;
  const double l = (pb - pa).norm();
  const Vec2 n = (pb - pa) / l;
  const double ldot = n.dot(vb - va);
  auto closed = [&](double w) {  // ∂r/∂p for ∂T/∂p = w; local order (xA, yA, θA, xB, yB, θB)
    LocalVec r(6);
    const Vec2 FB = -w * n;  // ∂F_B/∂p
    r << FB.x(), FB.y(), (rotation_derivative(tha) * da).dot(FB), -FB.x(), -FB.y(),
        -(rotation_derivative(thb) * db).dot(FB);
    return r;
  };
  const LocalVec dk = element_derivative(m, s, e, "spring_bodies.stiffness").dr;
  const LocalVec dc = element_derivative(m, s, e, "spring_bodies.damping").dr;
  const LocalVec dl0 = element_derivative(m, s, e, "spring_bodies.free_length").dr;
  const double ek = rel(dk, closed(l - l0)), ec = rel(dc, closed(ldot)),
               el0 = rel(dl0, closed(-k0));
  // the translation rows of B are −∂F_B/∂p exactly as the closed form states
  EXPECT_LT((Vec2(dk[3], dk[4]) - (l - l0) * n).norm(), 1e-12 * std::abs(l - l0));
  EXPECT_LT((Vec2(dc[3], dc[4]) - ldot * n).norm(), 1e-12 * std::abs(ldot));
  EXPECT_LT(ek, 1e-12);
  EXPECT_LT(ec, 1e-12);
  EXPECT_LT(el0, 1e-12);
  std::printf("spring ∂r/∂k, ∂r/∂c, ∂r/∂l0 vs closed form: %.2e %.2e %.2e\n", ek, ec, el0);
}

TEST_F(Fixture, RotationalSpringTorqueAndLoadParameterDerivativesMatchClosedForms) {
  double worst = 0;
  auto check = [&](const LocalVec& a, const LocalVec& ref, const char* what) {
    const double e = rel(a, ref);
    EXPECT_LT(e, 1e-12) << what << ": " << a.transpose() << " vs " << ref.transpose();
    worst = std::max(worst, e);
  };
  const auto& P = m.params().scalars;
  auto par = [&](const char* n) { return P[m.parameter_index(n)]; };
  // Rotational spring link–floater: M = k (θa − θb − θ0) + c (θ̇a − θ̇b); r_a = M, r_b = −M.
  {
    const int e = force_index(m, "rotational spring 'torsion_bodies'");
    const int a = m.find_rigid("link")->dof0 + 2, b = m.find_rigid("floater")->dof0 + 2;
    const double rel_angle = s.q[a] - s.q[b] - par("torsion_bodies.free_angle"),
                 rel_rate = s.v[a] - s.v[b];
    LocalVec r(2);
    check(element_derivative(m, s, e, "torsion_bodies.stiffness").dr,
          (r << rel_angle, -rel_angle).finished(), "∂/∂k");
    check(element_derivative(m, s, e, "torsion_bodies.damping").dr,
          (r << rel_rate, -rel_rate).finished(), "∂/∂c");
    const double k = par("torsion_bodies.stiffness");
    check(element_derivative(m, s, e, "torsion_bodies.free_angle").dr, (r << -k, k).finished(),
          "∂/∂θ0");
  }
  // Rotational spring slider–ground (θb ≡ 0), free angle defaulted to the initial angle 0.
  {
    const int e = force_index(m, "rotational spring 'torsion_ground'");
    const int a = m.find_rigid("slider")->dof0 + 2;
    EXPECT_EQ(par("torsion_ground.free_angle"), 0.0);
    LocalVec r(1);
    check(element_derivative(m, s, e, "torsion_ground.stiffness").dr, (r << s.q[a]).finished(),
          "∂/∂k (ground)");
    check(element_derivative(m, s, e, "torsion_ground.damping").dr, (r << s.v[a]).finished(),
          "∂/∂c (ground)");
  }
  // Torque: r_θ = −scale T(t): ∂r_θ/∂scale = −T(t) (T: the same tabulated law, built here).
  {
    const int e = force_index(m, "torque 'motor'");
    Table1D law({0, 0.1, 0.3, 1}, {0.5, 2, -1, 0.2});
    LocalVec r(1);
    check(element_derivative(m, s, e, "motor.scale").dr, (r << -law.value(s.t)).finished(),
          "∂/∂scale (law)");
    check(element_derivative(m, s, force_index(m, "torque 'brake'"), "brake.scale").dr,
          (r << 0.7).finished(), "∂/∂scale (constant)");
  }
  // Point force (3, −2) at body offset (0.05, 0.01): ∂r/∂scale = −(F, (R′d)·F).
  {
    const int th = m.find_rigid("crank")->dof0 + 2;
    const Vec2 F(3, -2), Rd = rotation_derivative(s.q[th]) * Vec2(0.05, 0.01);
    LocalVec r(3);
    check(element_derivative(m, s, force_index(m, "force 'f_body'"), "f_body.scale").dr,
          (r << -F.x(), -F.y(), -Rd.dot(F)).finished(), "point force ∂/∂scale");
  }
  // Pressure: F = A P(θ + offset) u, u = (−1, 0): ∂r/∂A = −P u on the slider's translation rows.
  {
    const int e = force_index(m, "pressure 'gas'");
    const int th_crank = m.find_rigid("crank")->dof0 + 2;
    Table1D tab({0, 1, 2.5, 4}, {1e5, 3e5, 2e5, 1e5}, Table1D::Interp::kCubic, 4);
    const double Pv = tab.value(s.q[th_crank] + 0.1);
    const Vec2 u(-1, 0),
        Rd = rotation_derivative(s.q[m.find_rigid("slider")->dof0 + 2]) * Vec2(0.01, 0);
    LocalVec r(4);  // (x, y, θ of the slider, θ of the crank: the argument, no force)
    check(element_derivative(m, s, e, "gas.area").dr,
          (r << -Pv * u.x(), -Pv * u.y(), -Pv * u.dot(Rd), 0).finished(), "pressure ∂/∂area");
  }
  // Node mass: ∂r/∂m = q̈ − g.
  {
    const ElementAt x =
        element_derivative(m, s, force_index(m, "point mass 'm_node'"), "m_node.mass");
    LocalVec r(2);
    check(x.dr, (r << x.ls.a[0] - 0.3, x.ls.a[1] + 9.81).finished(), "node mass ∂/∂m");
  }
  // Rigid inertia (methods.md): r_xy = m (ẍ + θ̈ R′c − θ̇² R c − g), r_θ = (J_c + m|c|²) θ̈ + m
  // (R′c)·(ẍ − g).
  {
    const RigidBody& b = *m.find_rigid("crank");
    const int e = force_index(m, "rigid body 'crank'");
    const Vec2 c(0.02, 0.01), g(0.3, -9.81), acc = s.a.segment<2>(b.dof0);
    const double th = s.q[b.dof0 + 2], w = s.v[b.dof0 + 2], al = s.a[b.dof0 + 2];
    const Vec2 Rc = rotation(th) * c, Rpc = rotation_derivative(th) * c,
               rxy = acc + al * Rpc - w * w * Rc - g;
    LocalVec r(3);
    check(element_derivative(m, s, e, "crank.mass").dr,
          (r << rxy.x(), rxy.y(), c.squaredNorm() * al + Rpc.dot(acc - g)).finished(),
          "rigid ∂/∂m");
    check(element_derivative(m, s, e, "crank.inertia").dr, (r << 0, 0, al).finished(),
          "rigid ∂/∂J");
  }
  std::printf(
      "∂r/∂p vs closed forms (rotational springs, torques, point force, pressure, masses): worst "
      "%.2e\n",
      worst);
}

TEST_F(Fixture, FlexibleParameterDerivativesFollowFromLinearity) {
  // r_e is linear in E0, ρ0 and t (eq. 3: E_e = μ E0, ρ_e = μ ρ0; f_int and the consistent mass
  // ∝ t): ∂r/∂E0 = (r(E0) − r(E0 = 0))/E0 and likewise for ρ0; ∂r/∂t = r/t. ν is checked by the
  // central differences above. The references carry the round-off of r_e: for ρ0 the inertia
  // part is about 1e-3 of ‖r_e‖ (the internal force dominates) at this state, a floor of ~1e3 ε.
  double worst = 0;
  for (const std::string plate : {"plate", "tri_plate"}) {
    const FlexibleBody& b = *m.find_flexible(plate);
    for (int el = 0; el < b.mesh.num_elements(); ++el) {
      const int e = b.first_force + el;
      auto r_with = [&](const std::string& name, double v) {
        ModelParams p = m.params();
        p.scalars[m.parameter_index(name)] = v;
        LocalVec r;
        m.element_residual(e, s, p, r);
        return r;
      };
      for (const std::string nm : {plate + ".E", plate + ".rho"}) {
        const double v0 = m.params().scalars[m.parameter_index(nm)];
        const LocalVec ref = (r_with(nm, v0) - r_with(nm, 0.0)) / v0;
        const double err = rel(element_derivative(m, s, e, nm).dr, ref);
        EXPECT_LT(err, 1e-10) << nm << ", element " << el;
        worst = std::max(worst, err);
      }
      const std::string th = plate + ".thickness";
      const double t0 = m.params().scalars[m.parameter_index(th)];
      const double err = rel(element_derivative(m, s, e, th).dr, r_with(th, t0) / t0);
      EXPECT_LT(err, 1e-12) << th << ", element " << el;
      worst = std::max(worst, err);
    }
  }
  std::printf("flexible ∂r/∂E0, ∂r/∂ρ0, ∂r/∂t vs linearity: worst %.2e\n", worst);
}
