// A spatial slider-crank in natural coordinates (mbs/spatial_joint.hpp) against independent
// references. The crank turns about the ground's x axis (revolute, with its joint angle), the
// connecting rod meets the crank pin in a spherical joint and the slider in a universal joint,
// and the slider moves along a line parallel to y, offset out of the crank's plane; gravity acts
// along −z. One degree of freedom, started by a crank speed, no driver and no damping:
//  - the motion against IDAS (GGL, BDF) at rtol = atol = 1e-10: the slider's position and the
//    crank angle, with the error of generalized-α falling at order 2;
//  - mechanical energy: conserved by IDAS to its tolerance; by generalized-α (ρ∞ = 0.8,
//    numerically dissipative) to within a drift that falls at order 2;
//  - the position-level closure of the loop in closed form: y_slider = y_pin + √(L² − Δx² −
//  z_pin²).
#include <gtest/gtest.h>

#include <cmath>

#include "lsmbs/integrators/idas_ggl.hpp"
#include "lsmbs/integrators/initial_state.hpp"
#include "lsmbs/mbs/model_builder.hpp"
#include "lsmbs/mbs/spatial_joint.hpp"
#include "support/spatial_models.hpp"

using namespace lsmbs;

namespace {

constexpr double kCrank = 0.1, kRod = 0.3, kG = 9.81;

struct SliderCrank {
  Model model;
  int crank = 0, rod = 0, slider = 0, theta = 0;
  std::array<double, 3> mass = {0.2, 0.5, 0.3};
  std::array<Vec3, 3> I = {Vec3(1.67e-4, 1e-6, 1.67e-4), Vec3(3.75e-3, 3.75e-3, 1e-5),
                           Vec3(1e-4, 1e-4, 1e-4)};
  std::array<int, 3> dof{};
  State s0;

  double offset = 0.2;  // of the slider's line from the crank's plane (0: a planar mechanism)

  explicit SliderCrank(double omega0, double offset_ = 0.2) : offset(offset_) {
    const Vec3 g(0, 0, -kG), P(0, kCrank, 0);
    const double kOffset = offset;
    const Vec3 S(kOffset, kCrank + std::sqrt(kRod * kRod - kOffset * kOffset), 0);
    const Vec3 dir = (S - P) / kRod;
    Mat3 Rrod;
    Rrod.col(0) = Vec3::UnitZ();
    Rrod.col(2) = dir;
    Rrod.col(1) = dir.cross(Vec3::UnitZ());
    const SpatialPose pc{P / 2, Mat3::Identity()}, pr{(P + S) / 2, Rrod}, ps{S, Mat3::Identity()},
        pg{};
    const char* names[] = {"crank", "rod", "slider"};
    for (int b = 0; b < 3; ++b)
      dof[static_cast<size_t>(b)] = checks::add_body(model, names[b], mass[static_cast<size_t>(b)],
                                                     I[static_cast<size_t>(b)], g);
    crank = dof[0], rod = dof[1], slider = dof[2];
    theta = model.add_dofs(1, "crank.angle");
    const SpatialBody G{}, C{crank}, R{rod}, Sl{slider};
    const auto add = [&](std::vector<std::unique_ptr<ConstraintElement>> cs, const char* name) {
      for (auto& c : cs) {
        c->set_name(name);
        model.add_constraint(std::move(c));
      }
    };
    add(make_spatial_joint(SpatialJointKind::kRevolute, G, pg, C, pc,
                           SpatialJointFrame::about(Vec3::Zero(), Vec3::UnitX()), theta),
        "crank_bearing");
    add(make_spatial_joint(SpatialJointKind::kSpherical, C, pc, R, pr,
                           SpatialJointFrame::about(P, Vec3::UnitZ())),
        "crank_pin");
    // the cross's axes: z on the slider, dir × z on the rod
    add(make_spatial_joint(SpatialJointKind::kUniversal, Sl, ps, R, pr,
                           SpatialJointFrame::about(S, dir)),
        "wrist_pin");
    add(make_spatial_joint(SpatialJointKind::kPrismatic, G, pg, Sl, ps,
                           SpatialJointFrame::about(S, Vec3::UnitY())),
        "slide");
    model.finalize();
    s0 = checks::zero_state(model);
    pc.write(crank, s0.q);
    pr.write(rod, s0.q);
    ps.write(slider, s0.q);
    // the crank's speed is given; every other rate follows from the constraints
    s0.v[theta] = omega0;
    std::vector<char> held(static_cast<size_t>(model.nq()), 0);
    held[static_cast<size_t>(theta)] = 1;
    SparseLU lu;
    lu.analyze(model.pattern());
    ProjectionReport rep;
    const Status st = project_initial_state(model, model.params(), s0, lu, 1e-13, &rep, &held);
    EXPECT_TRUE(st.ok()) << st.message;
  }

  double energy(const State& s) const {
    double E = 0;
    for (int b = 0; b < 3; ++b) {
      const int d = dof[static_cast<size_t>(b)];
      const Vec3 J = SpatialRigidInertia::second_moments(I[static_cast<size_t>(b)]);
      E += 0.5 * mass[static_cast<size_t>(b)] * s.v.segment<3>(d).squaredNorm();
      for (int k = 0; k < 3; ++k) E += 0.5 * J[k] * s.v.segment<3>(d + 3 + 3 * k).squaredNorm();
      E += mass[static_cast<size_t>(b)] * kG * s.q[d + 2];
    }
    return E;
  }
};

struct Trace {
  std::vector<double> t, y, theta, energy, closure;
  std::vector<std::string> warnings;  // the integrator's
};

void record(const SliderCrank& m, const State& s, Trace& tr) {
  tr.t.push_back(s.t);
  tr.y.push_back(s.q[m.slider + 1]);
  tr.theta.push_back(s.q[m.theta]);
  tr.energy.push_back(m.energy(s));
  // crank pin from the crank's frame, and the loop closed in closed form
  const SpatialPose C = SpatialPose::read(m.crank, s.q);
  const Vec3 pin = C.r + C.R * Vec3(0, kCrank / 2, 0);
  const double y = pin.y() + std::sqrt(kRod * kRod - m.offset * m.offset - pin.z() * pin.z());
  tr.closure.push_back(std::abs(y - s.q[m.slider + 1]));
}

constexpr double kOmega0 = 30, kTEnd = 0.6, kHOut = 0.01;

Trace run_alpha(double h, double omega0 = kOmega0, double t_end = kTEnd, double rho_inf = 0.8,
                double offset = 0.2) {
  SliderCrank m(omega0, offset);
  GeneralizedAlphaOptions o;
  o.h = h;
  o.t_end = t_end;
  o.rho_inf = rho_inf;
  struct Obs : checks::GridRecorder {
    const SliderCrank* m = nullptr;
    Trace tr;
    void record(const State& s) override {  // on IDAS's output grid
      if (std::abs(s.t / kHOut - std::round(s.t / kHOut)) < 1e-6) ::record(*m, s, tr);
    }
  } obs;
  obs.m = &m;
  const IntegratorSummary run = GeneralizedAlpha(o).run(m.model, m.model.params(), m.s0, {&obs});
  if (rho_inf <= 0.9) EXPECT_TRUE(run.ok) << run.message;
  obs.tr.warnings = run.warnings();
  return obs.tr;
}

Trace run_idas(double omega0 = kOmega0, double t_end = kTEnd, double offset = 0.2) {
  SliderCrank m(omega0, offset);
  IdasOptions o = IdasOptions::reference();
  o.rtol = o.atol = 1e-10;
  o.h_out = kHOut;
  o.t_end = t_end;
  Trace tr;
  const IdasStats st = IdasGGL(m.model, m.model.params(), o)
                           .run(m.s0, [&](const State& s, const Mat*, const Mat*, const Mat*,
                                          const Mat*) { record(m, s, tr); });
  EXPECT_TRUE(st.ok) << st.message;
  return tr;
}

double max_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double e = 0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) e = std::max(e, std::abs(a[i] - b[i]));
  return e;
}

double drift(const std::vector<double>& e) {
  double d = 0;
  for (double x : e) d = std::max(d, std::abs(x - e.front()));
  return d;
}

}  // namespace

TEST(SpatialSliderCrank, AgreesWithIdasAndConservesEnergyAtOrderTwo) {
  const Trace ref = run_idas();
  ASSERT_EQ(ref.t.size(), static_cast<size_t>(kTEnd / kHOut + 1.5));
  const double crank_turns = ref.theta.back() / (2 * std::numbers::pi);
  EXPECT_GT(crank_turns, 1.5);  // the crank goes round, through both dead centres
  const double energy_scale = std::abs(ref.energy.front());
  EXPECT_LT(drift(ref.energy) / energy_scale, 1e-7);
  EXPECT_LT(*std::max_element(ref.closure.begin(), ref.closure.end()), 1e-10);

  const Trace coarse = run_alpha(1e-3), fine = run_alpha(5e-4);
  EXPECT_TRUE(coarse.warnings.empty());  // ωh ≤ 0.05 here
  ASSERT_EQ(fine.t.size(), ref.t.size());
  const double ey1 = max_diff(coarse.y, ref.y), ey2 = max_diff(fine.y, ref.y);
  const double et1 = max_diff(coarse.theta, ref.theta), et2 = max_diff(fine.theta, ref.theta);
  const double ee1 = drift(coarse.energy), ee2 = drift(fine.energy);
  std::printf(
      "slider y error %.3e / %.3e m (order %.2f), crank angle %.3e / %.3e rad (%.2f),\n"
      "energy drift %.3e / %.3e J of %.4f J (%.2f), IDAS drift %.2e J, %.2f turns\n",
      ey1, ey2, std::log2(ey1 / ey2), et1, et2, std::log2(et1 / et2), ee1, ee2, energy_scale,
      std::log2(ee1 / ee2), drift(ref.energy), crank_turns);
  EXPECT_LT(ey2, 1e-3 * kRod);
  EXPECT_NEAR(std::log2(ey1 / ey2), 2.0, 0.3);
  EXPECT_NEAR(std::log2(et1 / et2), 2.0, 0.3);
  EXPECT_GT(std::log2(ee1 / ee2), 1.7);
  EXPECT_LT(*std::max_element(fine.closure.begin(), fine.closure.end()), 1e-10);
}

// The paper's crank speed (4000 rpm) and step (h = 2.5e-4 s): ωh = 0.105, at the stability limit
// measured for a free spinning body in natural coordinates (docs/methods.md, "Spatial rigid
// bodies"). With ρ∞ = 0.8 and 0.9 the crank stays stable there, its energy and phase errors
// against IDAS falling at order 2 with h; they are generalized-α's own, of the size the planar
// angle coordinates give (next test). ρ∞ = 0.95 diverges at this step (printed, not asserted).
TEST(SpatialSliderCrank, StableAtThePapersCrankSpeedAndStep) {
  const double omega0 = 4000 * 2 * std::numbers::pi / 60, t_end = 0.06;
  const Trace ref = run_idas(omega0, t_end);
  const double E = std::abs(ref.energy.front());
  for (const double rho : {0.8, 0.9, 0.95}) {
    const Trace a = run_alpha(2.5e-4, omega0, t_end, rho);
    const Trace b = run_alpha(1.25e-4, omega0, t_end, rho);
    const double ya = max_diff(a.y, ref.y), yb = max_diff(b.y, ref.y);
    const double ea = drift(a.energy) / E, eb = drift(b.energy) / E;
    std::printf(
        "rho_inf %.2f: %.2f turns, slider y error %.3e / %.3e m, energy drift %.3e / %.3e "
        "(relative), IDAS %.1e\n",
        rho, ref.theta.back() / (2 * std::numbers::pi), ya, yb, ea, eb, drift(ref.energy) / E);
    // ωh ≈ 0.1 at h = 0.25 ms (the free crank's speed varies about its start): at the limit of
    // ρ∞ = 0.8, beyond those of 0.9 and 0.95 (0.05, 0.03), which are warned (with 0.95 the
    // diverging rod's spin is the largest)
    if (rho > 0.8) {
      ASSERT_FALSE(a.warnings.empty());
      EXPECT_NE(a.warnings[0].find(rho > 0.9 ? "turned at omega h"
                                             : "spatial body 'crank' turned "
                                               "at omega h = 0.106"),
                std::string::npos)
          << a.warnings[0];
      std::printf("  %s\n", a.warnings[0].c_str());
    }
    if (rho > 0.9) continue;
    EXPECT_LT(ea, 5e-2);
    EXPECT_NEAR(std::log2(ya / yb), 2.0, 0.3);
    EXPECT_NEAR(std::log2(ea / eb), 2.0, 0.3);
  }
}

namespace {

// The same mechanism with the slider's line in the crank's plane, built as a planar model: the
// spatial y–z plane is the planar x–y plane, the crank and the rod turn about their principal
// axes along the spatial x (moments I₁ and I₂).
Trace run_planar(double h, double omega0, double t_end) {
  const SliderCrank m3(omega0, 0.0);
  ModelBuilder b;
  b.set_gravity(Vec2(0, -kG));
  RigidBodyOptions crank;
  crank.mass = m3.mass[0], crank.inertia = m3.I[0][0];
  crank.position = Vec2(kCrank / 2, 0), crank.angular_velocity = omega0;
  b.rigid_body("crank", crank);
  RigidBodyOptions rod;
  rod.mass = m3.mass[1], rod.inertia = m3.I[1][1];
  rod.position = Vec2(kCrank + kRod / 2, 0);
  b.rigid_body("rod", rod);
  RigidBodyOptions slider;
  slider.mass = m3.mass[2], slider.inertia = m3.I[2][2];
  slider.position = Vec2(kCrank + kRod, 0);
  b.rigid_body("slider", slider);
  b.revolute("bearing", Point::at("crank", Vec2(-kCrank / 2, 0)));
  b.revolute("pin", Point::at("crank", Vec2(kCrank / 2, 0)), Point::at("rod", Vec2(-kRod / 2, 0)));
  b.revolute("wrist", Point::at("rod", Vec2(kRod / 2, 0)), Point::at("slider"));
  b.prismatic("slide", Point::at("slider"), Vec2(1, 0));
  const int theta = b.angle_dof("crank"), x = b.rigid("slider").dof0;
  const auto model = b.build();
  State s0 = b.initial_state();
  SparseLU lu;
  lu.analyze(model->pattern());
  EXPECT_TRUE(
      project_initial_state(*model, model->params(), s0, lu, 1e-13, nullptr, &b.held_velocities())
          .ok());
  GeneralizedAlphaOptions o;
  o.h = h;
  o.t_end = t_end;
  struct Obs : checks::GridRecorder {
    int theta = 0, x = 0;
    Trace tr;
    void record(const State& s) override {
      if (std::abs(s.t / kHOut - std::round(s.t / kHOut)) > 1e-6) return;
      tr.t.push_back(s.t);
      tr.y.push_back(s.q[x]);
      tr.theta.push_back(s.q[theta]);
    }
  } obs;
  obs.theta = theta, obs.x = x;
  EXPECT_TRUE(GeneralizedAlpha(o).run(*model, model->params(), s0, {&obs}).ok);
  return obs.tr;
}

}  // namespace

// A planar mechanism written in natural coordinates against the same mechanism in planar angle
// coordinates, both integrated by generalized-α (ρ∞ = 0.8) and compared with IDAS on the spatial
// model. Both converge to it with errors of the same size; the difference between them is the
// discretization's (order 2, about 1 % of either's error), not round-off: the planar path
// integrates a rotation about a fixed axis in its angle, natural coordinates by the chords of
// their unit vectors (docs/methods.md, "Spatial rigid bodies").
TEST(SpatialSliderCrank, PlanarAsSpatialAgreesWithThePlanarModelAtOrderTwo) {
  const double omega0 = 4000 * 2 * std::numbers::pi / 60, t_end = 0.06;
  const Trace ref = run_idas(omega0, t_end, 0.0);
  const Trace s1 = run_alpha(2.5e-4, omega0, t_end, 0.8, 0.0);
  const Trace s2 = run_alpha(1.25e-4, omega0, t_end, 0.8, 0.0);
  const Trace p1 = run_planar(2.5e-4, omega0, t_end), p2 = run_planar(1.25e-4, omega0, t_end);
  ASSERT_EQ(p2.y.size(), ref.y.size());
  const double es1 = max_diff(s1.y, ref.y), es2 = max_diff(s2.y, ref.y);
  const double ep1 = max_diff(p1.y, ref.y), ep2 = max_diff(p2.y, ref.y);
  const double d1 = max_diff(s1.y, p1.y), d2 = max_diff(s2.y, p2.y);
  std::printf(
      "slider position against IDAS, h = 2.5e-4 / 1.25e-4 s: spatial %.3e / %.3e m, "
      "planar %.3e / %.3e m;\nspatial − planar %.3e / %.3e m (order %.2f); crank angle "
      "spatial − planar %.3e rad\n",
      es1, es2, ep1, ep2, d1, d2, std::log2(d1 / d2), max_diff(s2.theta, p2.theta));
  EXPECT_NEAR(std::log2(es1 / es2), 2.0, 0.3);
  EXPECT_NEAR(std::log2(d1 / d2), 2.0, 0.3);
  EXPECT_LT(d2, 0.05 * ep2);
}
