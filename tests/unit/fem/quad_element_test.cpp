// Plane-stress quad (total Lagrangian, St Venant–Kirchhoff): the internal force is the
// gradient of the strain energy, the tangent is the derivative of the force (central finite
// differences), a rigid rotation produces no force, and the patch test holds exactly.
#include "lsmbs/fem/quad_element.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lsmbs/core/error.hpp"

using namespace lsmbs;

namespace {

std::array<Vec2, 4> distorted_quad() {
  return {Vec2(0.0, 0.0), Vec2(0.012, 0.001), Vec2(0.010, 0.009), Vec2(-0.001, 0.007)};
}

QuadElement::Vec8 deformed(const std::array<Vec2, 4>& X, unsigned seed, double amp) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> u(-amp, amp);
  QuadElement::Vec8 x;
  const Mat2 R = rotation(0.7);
  for (int i = 0; i < 4; ++i) {
    const Vec2 p = R * X[i] + Vec2(0.3, -0.2);
    x[2 * i] = p.x() + u(g);
    x[2 * i + 1] = p.y() + u(g);
  }
  return x;
}

class QuadElementTest : public ::testing::TestWithParam<QuadIntegration> {};

}  // namespace

TEST_P(QuadElementTest, InternalForceIsTheGradientOfTheStrainEnergy) {
  const auto X = distorted_quad();
  QuadElement el(X, GetParam());
  const double E = 72e9, nu = 0.3, t = 0.0025;
  const auto x = deformed(X, 1, 4e-4);
  QuadElement::Vec8 f;
  el.internal_force(x, E, nu, t, f, nullptr);
  QuadElement::Vec8 g;
  const double h = 1e-7;
  for (int i = 0; i < 8; ++i) {
    auto xp = x, xm = x;
    xp[i] += h;
    xm[i] -= h;
    g[i] = (el.strain_energy(xp, E, nu, t) - el.strain_energy(xm, E, nu, t)) / (2 * h);
  }
  EXPECT_LT((f - g).norm() / f.norm(), 1e-6)
      << "f = " << f.transpose() << "\ng = " << g.transpose();
}

TEST_P(QuadElementTest, TangentIsTheDerivativeOfTheInternalForce) {
  const auto X = distorted_quad();
  QuadElement el(X, GetParam());
  const double E = 210e9, nu = 0.3, t = 0.01;
  const auto x = deformed(X, 2, 5e-4);
  QuadElement::Vec8 f;
  QuadElement::Mat8 K, Kfd;
  el.internal_force(x, E, nu, t, f, &K);
  const double h = 1e-8;
  for (int j = 0; j < 8; ++j) {
    auto xp = x, xm = x;
    xp[j] += h;
    xm[j] -= h;
    QuadElement::Vec8 fp, fm;
    el.internal_force(xp, E, nu, t, fp, nullptr);
    el.internal_force(xm, E, nu, t, fm, nullptr);
    Kfd.col(j) = (fp - fm) / (2 * h);
  }
  EXPECT_LT((K - Kfd).norm() / K.norm(), 1e-6);
  EXPECT_LT((K - K.transpose()).norm() / K.norm(), 1e-12) << "the SVK tangent is symmetric";
}

TEST_P(QuadElementTest, RigidRotationByNinetyDegreesProducesNoInternalForce) {
  const auto X = distorted_quad();
  QuadElement el(X, GetParam());
  QuadElement::Vec8 x, f;
  QuadElement::Mat8 K;
  for (int i = 0; i < 4; ++i) x.segment<2>(2 * i) = rotation(M_PI / 2) * X[i] + Vec2(1.0, 2.0);
  el.internal_force(x, 72e9, 0.3, 0.0025, f, &K);
  // Reference: the force of a 1e-3 strain, to make the comparison scale-aware.
  QuadElement::Vec8 xs, fs;
  for (int i = 0; i < 4; ++i) xs.segment<2>(2 * i) = Vec2(1.001 * X[i].x(), X[i].y());
  el.internal_force(xs, 72e9, 0.3, 0.0025, fs, nullptr);
  EXPECT_LT(f.norm(), 1e-10 * fs.norm());
  // The rotated element has two zero-energy modes per rigid motion direction: K x_rigid = 0.
  QuadElement::Vec8 translation;
  for (int i = 0; i < 4; ++i) translation.segment<2>(2 * i) = Vec2(1, 0);
  EXPECT_LT((K * translation).norm(), 1e-6 * K.norm());
}

// MacNeal–Harder style patch: a unit square split into five distorted quads. For an affine
// deformation x = F X + c (any F, even large), every element has the same constant Green
// strain, so the exact solution is reproduced: the assembled internal force vanishes at the
// interior nodes, and the boundary reactions equal the resultant tractions P·N on each edge.
TEST_P(QuadElementTest, PatchTestIsPassedExactlyForAffineDeformations) {
  const std::vector<Vec2> X = {
      {0, 0},       {0.24, 0},    {0.24, 0.12}, {0, 0.12},      // outer corners
      {0.04, 0.02}, {0.18, 0.03}, {0.16, 0.08}, {0.08, 0.08}};  // interior
  const std::vector<std::array<int, 4>> quads = {
      {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}, {4, 5, 6, 7}};
  Mat2 F;
  F << 1.02, 0.05, -0.03, 0.97;
  const Vec2 c(0.5, -0.25);
  const double E = 1e9, nu = 0.25, t = 0.001;
  Vec fglob = Vec::Zero(16);
  for (const auto& q : quads) {
    QuadElement el({X[q[0]], X[q[1]], X[q[2]], X[q[3]]}, GetParam());
    QuadElement::Vec8 x, f;
    for (int i = 0; i < 4; ++i) x.segment<2>(2 * i) = F * X[q[i]] + c;
    el.internal_force(x, E, nu, t, f, nullptr);
    for (int i = 0; i < 4; ++i) fglob.segment<2>(2 * q[i]) += f.segment<2>(2 * i);
  }
  // Exact first Piola stress P = F S, S = D E.
  const Mat2 C = F.transpose() * F;
  const double E11 = 0.5 * (C(0, 0) - 1), E22 = 0.5 * (C(1, 1) - 1), E12 = C(0, 1) / 2;
  const double d = E / (1 - nu * nu);
  Mat2 S;
  S << d * (E11 + nu * E22), d * (1 - nu) * E12, d * (1 - nu) * E12, d * (E22 + nu * E11);
  const Mat2 P = F * S;
  double scale = (P * Vec2(0.12, 0) * t).norm();
  for (int i = 4; i < 8; ++i)
    EXPECT_LT(fglob.segment<2>(2 * i).norm(), 1e-9 * scale) << "interior node " << i;
  // Corner 1 (x = 0.24, y = 0) carries half of the bottom edge and half of the right edge.
  const Vec2 expected = 0.5 * t * (P * Vec2(0, -1) * 0.24 + P * Vec2(1, 0) * 0.12);
  EXPECT_LT((fglob.segment<2>(2) - expected).norm(), 1e-9 * scale);
}

INSTANTIATE_TEST_SUITE_P(Integration, QuadElementTest,
                         ::testing::Values(QuadIntegration::kFull,
                                           QuadIntegration::kSelectiveShear),
                         [](const auto& info) {
                           return info.param == QuadIntegration::kFull ? "Full" : "SelectiveShear";
                         });

TEST(QuadElement, ConsistentMassIntegratesTheAreaExactly) {
  QuadElement el(distorted_quad(), QuadIntegration::kFull);
  // Σ_IJ ∫ N_I N_J = ∫ 1 = area (shoelace formula).
  const auto X = distorted_quad();
  double a = 0;
  for (int i = 0; i < 4; ++i) a += X[i].x() * X[(i + 1) % 4].y() - X[(i + 1) % 4].x() * X[i].y();
  EXPECT_NEAR(el.unit_mass().sum(), 0.5 * a, 1e-15);
  EXPECT_NEAR(el.area(), 0.5 * a, 1e-15);
}

namespace {

// ∫ N_I N_J dA in closed form. The bilinear map x(ξ, η) = Σ N_I x_I has x_ξ = c1 + c2 η,
// x_η = c3 + c2 ξ (likewise y with d1, d2, d3), so det J = a0 + a1 ξ + a2 η exactly (the ξη
// terms cancel), and with N_I = ¼(1 + ξ_I ξ)(1 + η_I η) the integral factorizes into
//   ∫ (1 + ξ_I ξ)(1 + ξ_J ξ) dξ = 2 + ⅔ ξ_I ξ_J,   ∫ ξ (1 + ξ_I ξ)(1 + ξ_J ξ) dξ = ⅔ (ξ_I + ξ_J).
Eigen::Matrix4d closed_form_unit_mass(const std::array<Vec2, 4>& X,
                                      Eigen::Vector4d* shape_integrals) {
  const double xi[4] = {-1, 1, 1, -1}, eta[4] = {-1, -1, 1, 1};
  Vec2 c1 = Vec2::Zero(), c2 = Vec2::Zero(), c3 = Vec2::Zero();
  for (int I = 0; I < 4; ++I) {
    c1 += 0.25 * xi[I] * X[I];
    c2 += 0.25 * xi[I] * eta[I] * X[I];
    c3 += 0.25 * eta[I] * X[I];
  }
  const double a0 = c1.x() * c3.y() - c3.x() * c1.y(), a1 = c1.x() * c2.y() - c2.x() * c1.y(),
               a2 = c2.x() * c3.y() - c3.x() * c2.y();
  Eigen::Matrix4d M;
  for (int I = 0; I < 4; ++I) {
    for (int J = 0; J < 4; ++J) {
      const double X0 = 2 + 2.0 / 3 * xi[I] * xi[J], X1 = 2.0 / 3 * (xi[I] + xi[J]);
      const double Y0 = 2 + 2.0 / 3 * eta[I] * eta[J], Y1 = 2.0 / 3 * (eta[I] + eta[J]);
      M(I, J) = (a0 * X0 * Y0 + a1 * X1 * Y0 + a2 * X0 * Y1) / 16;
    }
    (*shape_integrals)[I] = (4 * a0 + a1 * 4.0 / 3 * xi[I] + a2 * 4.0 / 3 * eta[I]) / 4;
  }
  return M;
}

}  // namespace

TEST(QuadElement, ConsistentMassEqualsTheClosedForm) {
  // a general (non-parallelogram) quad, a rectangle (textbook: A/36 [4 2 1 2; 2 4 2 1; …]) and a
  // parallelogram; relative to the largest entry, round-off of ~20 operations
  const std::array<Vec2, 4> rect = {Vec2(0.1, 0.2), Vec2(0.13, 0.2), Vec2(0.13, 0.21),
                                    Vec2(0.1, 0.21)};
  const std::array<Vec2, 4> para = {Vec2(0, 0), Vec2(0.02, 0.003), Vec2(0.025, 0.013),
                                    Vec2(0.005, 0.01)};
  for (const auto& X : {distorted_quad(), rect, para})
    for (QuadIntegration integ : {QuadIntegration::kFull, QuadIntegration::kSelectiveShear}) {
      QuadElement el(X, integ);
      Eigen::Vector4d s;
      const Eigen::Matrix4d ref = closed_form_unit_mass(X, &s);
      const double scale = ref.cwiseAbs().maxCoeff();
      EXPECT_LT((el.unit_mass() - ref).cwiseAbs().maxCoeff(), 1e-14 * scale)
          << "unit mass\n"
          << el.unit_mass() << "\n"
          << ref;
      EXPECT_LT((el.shape_integrals() - s).cwiseAbs().maxCoeff(), 1e-14 * s.cwiseAbs().maxCoeff());
    }
  Eigen::Vector4d s;
  Eigen::Matrix4d textbook;
  textbook << 4, 2, 1, 2, 2, 4, 2, 1, 1, 2, 4, 2, 2, 1, 2, 4;
  textbook *= 0.03 * 0.01 / 36;
  EXPECT_LT((closed_form_unit_mass(rect, &s) - textbook).cwiseAbs().maxCoeff(),
            1e-14 * textbook.maxCoeff());
  EXPECT_LT(
      (QuadElement(rect, QuadIntegration::kFull).unit_mass() - textbook).cwiseAbs().maxCoeff(),
      1e-14 * textbook.maxCoeff());
}

TEST(QuadElement, InvertedElementIsRejected) {
  EXPECT_THROW(
      QuadElement({Vec2(0, 0), Vec2(0, 1), Vec2(1, 1), Vec2(1, 0)}, QuadIntegration::kFull), Error);
}

TEST(QuadElement, DeterminantOfTheDeformationGradientFollowsTheClosedForms) {
  const auto X = distorted_quad();
  auto map = [&](const Mat2& F) {  // x = F X + c at every node: a homogeneous deformation
    QuadElement::Vec8 x;
    for (int i = 0; i < 4; ++i) x.segment<2>(2 * i) = F * X[i] + Vec2(0.3, -0.2);
    return x;
  };
  const QuadElement el(X, QuadIntegration::kSelectiveShear);
  Mat2 stretch;
  stretch << 1.3, 0.2, 0.0, 0.7;  // det 0.91
  EXPECT_NEAR(el.min_det_F(map(rotation(0.7) * stretch)), 0.91, 1e-12);
  EXPECT_NEAR(el.min_det_F(map(Mat2::Identity())), 1.0, 1e-12);
  // a reflection: det F = −1, and the St Venant–Kirchhoff energy does not see it (E = 0), which
  // is why the integrators must reject such states
  Mat2 reflect;
  reflect << -1, 0, 0, 1;
  const auto xr = map(rotation(0.3) * reflect);
  EXPECT_NEAR(el.min_det_F(xr), -1.0, 1e-12);
  EXPECT_NEAR(el.strain_energy(xr, 70e9, 0.3, 1e-3), 0.0, 1e-9);
  // one node pushed through the opposite edge: some integration point inverts
  QuadElement::Vec8 x = map(Mat2::Identity());
  x.segment<2>(4) = Vec2(0.3 - 0.004, -0.2 - 0.004);  // node 2 moved past node 0
  EXPECT_LT(el.min_det_F(x), 0.0);
}
