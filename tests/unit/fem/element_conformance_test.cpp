// Conformance of every registered planar element type (fem/element_types.hpp) with the
// PlaneElement and CellShape contracts, as SUNDIALS tests every linear solver with one suite: a
// new element type registered is tested here without a line of its own. On a distorted cell, at
// a deformed state:
//  * the internal force is the gradient of the strain energy, and the tangent is the derivative
//    of the force, both against central differences; ∂f/∂ν likewise;
//  * a rigid rotation and translation of the reference configuration gives no force (objectivity);
//  * a homogeneous stretch gives the closed-form plane-stress stress at the centre (patch test),
//    and the centre stress's derivatives match central differences;
//  * the consistent mass sums to the area (∫ Σ N_I Σ N_J = A), the shape integrals to the area;
//  * the shape's area equals the element's, the sub-cell samples' weights sum to it at every
//    resolution and their first moments give the centroid, and the zero contour of a linear field
//    lies on its zero line.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "lsmbs/fem/element_types.hpp"

using namespace lsmbs;

namespace {

constexpr double kE = 70e9, kNu = 0.3, kT = 0.002;

// A distorted reference cell of the type's node count (counter-clockwise).
std::vector<Vec2> reference_cell(int n) {
  if (n == 3) return {Vec2(0.01, 0.02), Vec2(0.09, 0.0), Vec2(0.03, 0.07)};
  return {Vec2(0.0, 0.0), Vec2(0.1, 0.01), Vec2(0.11, 0.08), Vec2(-0.01, 0.06)};
}

// A deformed state: the reference rotated by 0.3 rad, translated, and strained a little.
std::vector<double> deformed(const std::vector<Vec2>& X) {
  const Mat2 R = rotation(0.3);
  Mat2 U;
  U << 1.004, 0.002, -0.001, 0.997;
  std::vector<double> x;
  for (const auto& p : X) {
    const Vec2 y = R * U * p + Vec2(0.5, -0.2);
    x.push_back(y.x()), x.push_back(y.y());
  }
  return x;
}

class Conformance : public testing::TestWithParam<int> {
 protected:
  const ElementType& type() const { return element_types()[static_cast<size_t>(GetParam())]; }
  std::unique_ptr<PlaneElement> make(const std::vector<Vec2>& X) const {
    return type().make(X.data(), ElementOptions{});
  }
};

TEST_P(Conformance, ForceIsTheEnergyGradientAndTheTangentItsDerivative) {
  const auto X = reference_cell(type().nodes);
  const auto el = make(X);
  ASSERT_EQ(el->num_nodes(), type().nodes);
  auto x = deformed(X);
  const int nd = el->num_dofs();
  std::vector<double> f(nd), K(nd * nd), fp(nd), fm(nd), dnu(nd);
  el->internal_force(x.data(), kE, kNu, kT, f.data(), K.data());
  double fmax = 0, kmax = 0;
  for (double v : f) fmax = std::max(fmax, std::abs(v));
  for (double v : K) kmax = std::max(kmax, std::abs(v));
  ASSERT_GT(fmax, 0);
  for (int k = 0; k < nd; ++k) {
    const double h = 1e-7 * 0.1, xk = x[k];
    x[k] = xk + h;
    const double Wp = el->strain_energy(x.data(), kE, kNu, kT);
    el->internal_force(x.data(), kE, kNu, kT, fp.data(), nullptr);
    x[k] = xk - h;
    const double Wm = el->strain_energy(x.data(), kE, kNu, kT);
    el->internal_force(x.data(), kE, kNu, kT, fm.data(), nullptr);
    x[k] = xk;
    EXPECT_NEAR((Wp - Wm) / (2 * h), f[k], 1e-6 * fmax) << type().name << " coordinate " << k;
    for (int i = 0; i < nd; ++i)
      EXPECT_NEAR((fp[i] - fm[i]) / (2 * h), K[k * nd + i], 1e-6 * kmax)
          << type().name << " K(" << i << ", " << k << ")";
  }
  // ∂f/∂ν by central differences in ν
  el->internal_force_nu_derivative(x.data(), kE, kNu, kT, dnu.data());
  el->internal_force(x.data(), kE, kNu + 1e-6, kT, fp.data(), nullptr);
  el->internal_force(x.data(), kE, kNu - 1e-6, kT, fm.data(), nullptr);
  for (int i = 0; i < nd; ++i)
    EXPECT_NEAR((fp[i] - fm[i]) / 2e-6, dnu[i], 1e-6 * fmax / 0.3) << type().name;
}

TEST_P(Conformance, RigidMotionGivesNoForceAndAStretchTheClosedFormStress) {
  const auto X = reference_cell(type().nodes);
  const auto el = make(X);
  const int nd = el->num_dofs();
  std::vector<double> x, f(nd);
  const Mat2 R = rotation(1.1);
  for (const auto& p : X) {
    const Vec2 y = R * p + Vec2(3, -4);
    x.push_back(y.x()), x.push_back(y.y());
  }
  el->internal_force(x.data(), kE, kNu, kT, f.data(), nullptr);
  for (double v : f) EXPECT_NEAR(v, 0, 1e-3) << type().name;  // vs forces of order E t h ≈ 1e7
  // uniaxial-strain patch: x = (1 + e) X, y = Y: E11 = e + e²/2, S = D E, σ = F S Fᵀ / J
  const double e = 1e-3;
  x.clear();
  for (const auto& p : X) x.push_back((1 + e) * p.x()), x.push_back(p.y());
  const double E11 = e + 0.5 * e * e, c = kE / (1 - kNu * kNu);
  const double S11 = c * E11, S22 = c * kNu * E11;
  const double s11 = (1 + e) * (1 + e) * S11 / (1 + e), s22 = S22 / (1 + e);
  const double vm = std::sqrt(s11 * s11 - s11 * s22 + s22 * s22);
  const PointStress ps = el->centre_stress(x.data(), kE, kNu, true);
  EXPECT_NEAR(ps.vm, vm, 1e-9 * vm) << type().name;
  // its derivatives against central differences
  for (int k = 0; k < nd; ++k) {
    const double h = 1e-9, xk = x[k];
    x[k] = xk + h;
    const double vp = el->centre_stress(x.data(), kE, kNu, false).vm;
    x[k] = xk - h;
    const double vmm = el->centre_stress(x.data(), kE, kNu, false).vm;
    x[k] = xk;
    EXPECT_NEAR((vp - vmm) / (2 * h), ps.dvm[k], 1e-5 * vm / 0.01) << type().name << " " << k;
  }
}

TEST_P(Conformance, MassShapeIntegralsAndSamplesMatchTheCellGeometry) {
  const auto X = reference_cell(type().nodes);
  const auto el = make(X);
  const double A = type().shape->area(X.data());
  EXPECT_NEAR(el->area(), A, 1e-15) << type().name;
  EXPECT_NEAR(el->unit_mass().sum(), A, 1e-15) << type().name;
  EXPECT_NEAR(el->shape_integrals().sum(), A, 1e-15) << type().name;
  EXPECT_TRUE(el->unit_mass().isApprox(el->unit_mass().transpose())) << type().name;
  // the centroid of the cell as a polygon (shoelace)
  Vec2 cen = Vec2::Zero();
  const int n = type().nodes;
  for (int k = 0; k < n; ++k) {
    const Vec2 a = X[k], b = X[(k + 1) % n];
    cen += (a + b) * (a.x() * b.y() - b.x() * a.y());
  }
  cen /= 6 * A;
  Vec2 err1 = Vec2::Zero();  // the error of the first moments with one sub-cell
  for (int sub : {1, 3, 8}) {
    std::vector<CellSample> s;
    type().shape->samples(X.data(), sub, s);
    double W = 0;
    Vec2 m = Vec2::Zero();
    for (const auto& p : s) W += p.w, m += p.w * p.x;
    EXPECT_NEAR(W, A, 1e-15) << type().name << " subgrid " << sub;
    // The midpoint rule integrates x det J exactly on affine sub-cells (a triangle's); on the
    // bilinear quadrilateral's parent square x det J is of degree ≤ 2 in each of ξ, η, where the
    // rule's error is (h²/24) ∫ Δf exactly: the error with n × n sub-cells is that of one cell
    // divided by n².
    const Vec2 err = m - W * cen;
    if (sub == 1) err1 = err;
    EXPECT_LT((err - err1 / (sub * sub)).norm(), 1e-15) << type().name << " subgrid " << sub;
    if (n == 3) EXPECT_LT(err.norm(), 1e-16) << type().name << " subgrid " << sub;
  }
}

TEST_P(Conformance, ContourOfALinearFieldLiesOnItsZeroLine) {
  const auto X = reference_cell(type().nodes);
  const Vec2 normal = Vec2(0.6, 0.8);
  const double offset = normal.dot(X[0] + X[1]) / 2;  // the line crosses the cell
  double phi[Cell::kMaxNodes];
  for (int k = 0; k < type().nodes; ++k) phi[k] = normal.dot(X[k]) - offset;
  std::vector<std::pair<Vec2, Vec2>> seg;
  type().shape->contour(X.data(), phi, seg);
  ASSERT_FALSE(seg.empty()) << type().name;
  for (const auto& [a, b] : seg) {
    EXPECT_NEAR(normal.dot(a) - offset, 0, 1e-15) << type().name;
    EXPECT_NEAR(normal.dot(b) - offset, 0, 1e-15) << type().name;
  }
}

TEST(ElementTypes, EveryTypeIsFoundByItsNameAndGmshNumber) {
  for (size_t i = 0; i < element_types().size(); ++i) {
    const ElementType& t = element_types()[i];
    CellType by_name, by_gmsh;
    ASSERT_EQ(element_type_named(t.name, &by_name), &t);
    ASSERT_EQ(element_type_for_gmsh(t.gmsh_type, &by_gmsh), &t);
    EXPECT_EQ(by_name.index, i);
    EXPECT_EQ(by_gmsh.index, i);
    EXPECT_EQ(t.shape->num_nodes(), t.nodes);
  }
  EXPECT_EQ(element_type_named("hex8"), nullptr);
}

INSTANTIATE_TEST_SUITE_P(EveryRegisteredType, Conformance,
                         testing::Range(0, static_cast<int>(element_types().size())),
                         [](const testing::TestParamInfo<int>& i) {
                           return std::string(element_types()[static_cast<size_t>(i.param)].name);
                         });

}  // namespace
