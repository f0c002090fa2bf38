// The GGL index-2 system that IDAS integrates (GglSystem), without SUNDIALS: its Jacobian
// F_y + c_j F_ẏ, its forward sensitivity residuals F_y y_p + F_ẏ ẏ_p + F_p and its adjoint
// residual against central differences of its own residual F(t, y, ẏ; p), at a random point off
// the constraint manifold (μ ≠ 0, Φ ≠ 0) with scales s₁, s₃, s₄ of different sizes, on the rigid
// pendulum and on a small flexible model (a plate pinned to ground, a driven rigid crank with an
// offset centre of mass pinned to the plate off its reference point, a spring–damper, gravity).
#include "lsmbs/integrators/ggl_system.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "support/pendulum.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

json flexible_case() {
  return R"({
  "name": "plate_and_crank",
  "gravity": [0.2, -9.81],
  "bodies": [
    {"name": "plate", "type": "flexible",
     "mesh": {"type": "rectangle", "origin": [0, -0.01], "size": [0.12, 0.02], "elements": [3, 1]},
     "material": {"E": 2e7, "nu": 0.3, "rho": 1200}, "thickness": 0.004},
    {"name": "crank", "type": "rigid", "position": [0.10089327021748787, 0.004089595866773209], "angle": 0.3, "mass": 1.5, "inertia": 2e-3,
     "com": [0.04, 0.02]}
  ],
  "joints": [
    {"name": "pin_ground", "type": "revolute", "a": {"body": "plate", "nearest": [0, 0]}, "b": "ground"},
    {"name": "pin_crank", "type": "revolute", "a": {"body": "plate", "nearest": [0.12, 0.01]},
     "b": {"body": "crank", "at": [0.02, 0]}},
    {"name": "drive", "type": "rotation_driver", "body": "crank",
     "law": {"type": "ramp", "from": 0.3, "speed": 20, "ramp_time": 0.1}}
  ],
  "forces": [
    {"name": "spring", "type": "spring_damper", "a": {"body": "crank", "at": [0.05, 0]},
     "b": {"body": "plate", "node": 1}, "stiffness": 300, "damping": 4, "free_length": 0.05}
  ],
  "simulation": {"t_end": 0.1, "h": 1e-3, "check_constraints": false}
})"_json;
}

// A model, its GGL system with scales of different sizes, and a random point (t, y, ẏ) near the
// initial configuration but off the constraint manifold.
struct GglPoint {
  Case cs;
  GglSystem ggl;
  double t = 0.037;
  Vec y, yp;
  explicit GglPoint(const json& j, unsigned seed) : cs(test::make_case(j)), ggl(*cs.model) {
    const Model& m = *cs.model;
    const int nq = m.nq(), nc = m.nc(), N = ggl.size();
    ggl.set_scales({.s1 = 3.7e2, .s3 = 1.3e4, .s4 = 0.61});
    std::mt19937 g(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    auto random = [&](int n, double scale) {
      return Vec(Vec::NullaryExpr(n, [&] { return scale * u(g); }));
    };
    y.resize(N);
    yp.resize(N);
    y << cs.initial.q + random(nq, 2e-3), random(nq, 1.0), random(nc, 10.0), random(nc, 1e-2);
    yp << random(nq, 1.0), random(nq, 10.0), random(nc, 1.0), random(nc, 1.0);
  }
  const Model& model() const { return *cs.model; }
  Vec F(const Vec& y_, const Vec& yp_, const ModelParams& p) {
    Vec f(ggl.size());
    EXPECT_TRUE(ggl.residual(p, t, y_.data(), yp_.data(), f.data()));
    return f;
  }
  Vec F(const Vec& y_, const Vec& yp_) { return F(y_, yp_, model().params()); }
  // ∂F/∂y (wrt_yp false) or ∂F/∂ẏ (true) by central differences with step h.
  Mat differences(bool wrt_yp, double h) {
    const int N = ggl.size();
    Mat D(N, N);
    for (int j = 0; j < N; ++j) {
      Vec a = wrt_yp ? yp : y, b = a;
      a[j] += h;
      b[j] -= h;
      D.col(j) = wrt_yp ? (F(y, a) - F(y, b)) / (2 * h) : (F(a, yp) - F(b, yp)) / (2 * h);
    }
    return D;
  }
  Mat jacobian(double cj) {
    return Mat(ggl.jacobian(model().params(), t, cj, y.data(), yp.data()));
  }
};

// Largest |a − ref| relative to the largest |ref| (the entries of F span many magnitudes; an
// entry-wise test would need a floor anyway), with the worst entry named.
double max_relative_error(const Mat& a, const Mat& ref, std::string* where = nullptr) {
  Eigen::Index i = 0, j = 0;
  const double err = (a - ref).cwiseAbs().maxCoeff(&i, &j);
  if (where) *where = "(" + std::to_string(i) + ", " + std::to_string(j) + ")";
  return err / ref.cwiseAbs().maxCoeff();
}

// Block-wise check: every one of the 4 × 4 blocks (rows F1–F4, columns q, v, λ, μ) against the
// largest entry of its block row in the reference, so that a small block (F4: s₄ ≈ 0.6) is not
// hidden by a large one (F3: s₃ Φ_q ≈ 1e4).
double worst_block_error(const GglSystem& ggl, const Mat& a, const Mat& ref, std::string& where) {
  const int nq = ggl.nq(), nc = ggl.nc();
  const int off[5] = {0, nq, 2 * nq, 2 * nq + nc, 2 * nq + 2 * nc};
  double worst = 0;
  for (int r = 0; r < 4; ++r) {
    const Eigen::Index rows = off[r + 1] - off[r];
    if (rows == 0) continue;
    const double scale = ref.middleRows(off[r], rows).cwiseAbs().maxCoeff();
    if (scale == 0) continue;
    const double e =
        (a.middleRows(off[r], rows) - ref.middleRows(off[r], rows)).cwiseAbs().maxCoeff() / scale;
    if (e > worst) worst = e, where = "rows F" + std::to_string(r + 1);
  }
  return worst;
}

void check_jacobian(GglPoint& pt, const char* name) {
  // F is linear in ẏ, λ and μ; in q and v the difference error is O(h²) against round-off O(ε/h).
  const Mat Dy = pt.differences(false, 1e-6), Dyp = pt.differences(true, 1e-3);
  const double cj = 2.9e3;
  const Mat J0 = pt.jacobian(0.0), Jc = pt.jacobian(cj);
  std::string w0, w1, w2;
  const double e_y = worst_block_error(pt.ggl, J0, Dy, w0);
  const double e_yp = worst_block_error(pt.ggl, (Jc - J0) / cj, Dyp, w1);
  const double e_all = worst_block_error(pt.ggl, Jc, Dy + cj * Dyp, w2);
  std::printf("%s (N = %d): F_y %.2e (%s), F_ẏ %.2e (%s), F_y + c_j F_ẏ %.2e (%s)\n", name,
              pt.ggl.size(), e_y, w0.c_str(), e_yp, w1.c_str(), e_all, w2.c_str());
  EXPECT_LT(e_y, 1e-7) << "F_y, " << w0;
  EXPECT_LT(e_yp, 1e-7) << "F_ẏ, " << w1;
  EXPECT_LT(e_all, 1e-7) << "F_y + c_j F_ẏ, " << w2;
}

// r = F_y yS + F_ẏ ẏS + F_p d against the derivative of F along (yS, ẏS, d) by central differences.
void check_sensitivity_residual(GglPoint& pt, const std::vector<ParamDirection>& dirs,
                                const char* name) {
  const int N = pt.ggl.size(), nv = static_cast<int>(dirs.size());
  std::mt19937 g(7);
  std::uniform_real_distribution<double> u(-1, 1);
  Mat yS = Mat::NullaryExpr(N, nv, [&] { return u(g); }),
      ypS = Mat::NullaryExpr(N, nv, [&] { return u(g); });
  Mat r(N, nv);
  std::vector<const double*> a(nv), b(nv);
  std::vector<double*> c(nv);
  for (int i = 0; i < nv; ++i)
    a[i] = yS.col(i).data(), b[i] = ypS.col(i).data(), c[i] = r.col(i).data();
  pt.ggl.sensitivity_residual(pt.model().params(), pt.t, pt.y.data(), pt.yp.data(), dirs, a, b, c);
  Mat ref(N, nv);
  const double h = 1e-6;
  for (int i = 0; i < nv; ++i) {
    ModelParams pp = pt.model().params(), pm = pp;
    add_direction(pp, dirs[i], h);
    add_direction(pm, dirs[i], -h);
    ref.col(i) = (pt.F(pt.y + h * yS.col(i), pt.yp + h * ypS.col(i), pp) -
                  pt.F(pt.y - h * yS.col(i), pt.yp - h * ypS.col(i), pm)) /
                 (2 * h);
  }
  std::string where;
  const double e = worst_block_error(pt.ggl, r, ref, where);
  std::printf("%s: sensitivity residuals of %d directions %.2e (%s)\n", name, nv, e, where.c_str());
  EXPECT_LT(e, 1e-7) << where;
}

// The adjoint residual is d/dt(F_ẏᵀ ξ) − F_yᵀ ξ + ∂g/∂y with F_ẏ = diag(s₁ I, M(q), 0, 0):
// F_ẏᵀ ξ̇ + [0; Ṁ ξ_v; 0; 0] − F_yᵀ ξ + [g_q; g_v; 0; 0], all from differences of F: F_y and
// F_ẏ as above, and Ṁ ξ_v = d/dτ (M(q + τ v) ξ_v) with M(q) ξ_v the F2 rows' derivative in v̇
// along ξ_v (F is linear in v̇). Returns the worst block error; `mass_rate_only`: ξ = (0, ξ_v,
// 0, 0), ξ̇ = 0, g = 0, and the v rows compared relative to |Ṁ ξ_v| (which the other terms
// would hide in the general check).
double adjoint_residual_error(GglPoint& pt, bool mass_rate_only, std::string& where) {
  const int nq = pt.ggl.nq(), N = pt.ggl.size();
  std::mt19937 g(11);
  std::uniform_real_distribution<double> u(-1, 1);
  Vec xi = Vec::NullaryExpr(N, [&] { return u(g); }),
      xid = Vec::NullaryExpr(N, [&] { return u(g); });
  Vec gq = Vec::NullaryExpr(nq, [&] { return u(g); }),
      gv = Vec::NullaryExpr(nq, [&] { return u(g); });
  if (mass_rate_only) {
    const Vec xv = xi.segment(nq, nq);
    xi.setZero();
    xi.segment(nq, nq) = xv;
    xid.setZero(), gq.setZero(), gv.setZero();
  }
  Vec r(N);
  EXPECT_TRUE(pt.ggl.adjoint_residual(pt.model().params(), pt.t, pt.y.data(), pt.yp.data(),
                                      xi.data(), xid.data(), gq, gv, r.data()));
  const Mat Dy = pt.differences(false, 1e-6), Dyp = pt.differences(true, 1e-3);
  auto mass_times_xi_v = [&](double tau) {  // M(q) ξ_v at q = y_q + τ v
    Vec y = pt.y, a = pt.yp;
    y.head(nq) += tau * pt.y.segment(nq, nq);
    a.segment(nq, nq) += xi.segment(nq, nq);
    return Vec((pt.F(y, a) - pt.F(y, pt.yp)).segment(nq, nq));
  };
  const double h = 1e-4;  // M(q) is smooth in q: a larger step keeps the round-off of M ξ_v small
  const Vec mdot_xi = (mass_times_xi_v(h) - mass_times_xi_v(-h)) / (2 * h);
  Vec ref = Dyp.transpose() * xid - Dy.transpose() * xi;
  ref.segment(nq, nq) += mdot_xi;
  ref.head(nq) += gq;
  ref.segment(nq, nq) += gv;
  if (!mass_rate_only) return worst_block_error(pt.ggl, r, ref, where);
  where = "rows v, |Ṁ ξ_v| = " + std::to_string(mdot_xi.norm()) +
          " of |r_v| = " + std::to_string(r.segment(nq, nq).norm());
  EXPECT_GT(mdot_xi.norm(), 1e-3 * r.segment(nq, nq).norm()) << "the mass rate must be visible";
  return (r - ref).segment(nq, nq).cwiseAbs().maxCoeff() / mdot_xi.cwiseAbs().maxCoeff();
}

}  // namespace

TEST(GglSystem, PendulumJacobianMatchesCentralDifferencesOfTheResidual) {
  GglPoint pt(test::Pendulum{}.json(1e-3), 1);
  check_jacobian(pt, "pendulum");
}

TEST(GglSystem, FlexibleModelJacobianMatchesCentralDifferencesOfTheResidual) {
  GglPoint pt(flexible_case(), 2);
  ASSERT_EQ(pt.model().flexible_bodies().size(), 1u);
  check_jacobian(pt, "plate and crank");
}

TEST(GglSystem, SensitivityResidualsAreTheDerivativeOfTheResidualAlongTheSensitivities) {
  {
    GglPoint pt(test::Pendulum{}.json(1e-3), 3);
    const Model& m = pt.model();
    ParamDirection mass, inertia;
    mass.scalars = {{m.parameter_index("bob.mass"), 1.0}};
    inertia.scalars = {{m.parameter_index("bob.inertia"), 0.01}};
    ASSERT_GE(mass.scalars[0].first, 0);
    ASSERT_GE(inertia.scalars[0].first, 0);
    check_sensitivity_residual(pt, {mass, inertia}, "pendulum");
  }
  {
    GglPoint pt(flexible_case(), 4);
    const Model& m = pt.model();
    ParamDirection density, stiffness;
    const int field = m.flexible_bodies()[0]->field;
    for (int e = 0; e < m.flexible_bodies()[0]->mesh.num_elements(); ++e)
      density.fields.push_back({field, e, 0.3 + 0.2 * e});
    stiffness.scalars = {{m.parameter_index("spring.stiffness"), 50.0},
                         {m.parameter_index("plate.E"), 3e6},
                         {m.parameter_index("crank.mass"), 0.1}};
    for (const auto& [j, v] : stiffness.scalars) ASSERT_GE(j, 0);
    check_sensitivity_residual(pt, {density, stiffness}, "plate and crank");
  }
}

TEST(GglSystem, AdjointResidualIsTheTransposedLinearizationPlusTheMassRate) {
  auto check = [](GglPoint& pt, const char* name) {
    std::string where;
    const double e = adjoint_residual_error(pt, false, where);
    std::printf("%s: adjoint residual %.2e (%s)\n", name, e, where.c_str());
    EXPECT_LT(e, 1e-7) << name << ", " << where;
  };
  GglPoint pendulum(test::Pendulum{}.json(1e-3), 5), pt(flexible_case(), 6);
  check(pendulum, "pendulum");
  check(pt, "plate and crank");
  // The crank's offset centre of mass makes M depend on q: the Ṁ ξ_v term on its own.
  std::string where;
  const double e = adjoint_residual_error(pt, true, where);
  std::printf("plate and crank: mass-rate term %.2e (%s)\n", e, where.c_str());
  EXPECT_LT(e, 1e-6) << where;
}
