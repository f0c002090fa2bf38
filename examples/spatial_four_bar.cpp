//                        lsmbs example 4: a spatial four-bar balanced by a spring
//
// Sample run:   build/examples/spatial_four_bar
//
// A spatial four-bar (RSSR type): the crank turns about the ground's z axis, driven at 2 rev/s;
// the rocker turns about a tilted ground axis, so that the linkage is not planar; the coupler has
// a spherical joint at the crank pin and a universal joint at the rocker (which holds its spin).
// A torsion spring on the rocker's joint angle stores and returns energy over the cycle. Its
// stiffness k is the design variable; the response is the RMS of the motor's torque over the
// second revolution, which gravity and the links' inertia load. The example builds the model with
// the ModelBuilder's spatial calls (natural coordinates, docs/methods.md "Spatial rigid bodies"),
// computes the response's gradient by the direct analytic method, and checks it against central
// differences of two more simulations. It then finds the stiffness that minimizes the RMS torque
// by the secant method on the exact gradient, and checks that the gradient vanishes there and
// that the optimum's RMS torque is below the one without a spring (k = 0). Exit 1 when a check
// fails.
#include <cmath>
#include <cstdio>
#include <numbers>

#include "lsmbs/mbs/model_builder.hpp"
#include "lsmbs/responses/spatial_measure.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

using namespace lsmbs;

namespace {

// A rotation whose third column is e3 and whose first is `hint` made perpendicular to e3.
Mat3 frame(const Vec3& e3, const Vec3& hint) {
  const Vec3 e1 = (hint - hint.dot(e3) * e3).normalized();
  Mat3 R;
  R << e1, e3.cross(e1), e3;
  return R;
}

SpatialBodyOptions rod(double m, double length, const Vec3& centre, const Mat3& R) {
  const double I = m * length * length / 12;  // a slender rod along its third axis
  return {.mass = m, .inertia = Vec3(I, I, 1e-3 * I), .position = centre, .orientation = R};
}

}  // namespace

int main() {
  // 1. The linkage (m, kg, s).
  const double a = 0.05, c = 0.09, omega = 4 * std::numbers::pi;
  const Vec3 G(0.12, 0.10, 0.04), n = Vec3(0, 1, 1).normalized(), P0(a, 0, 0);
  const Vec3 u = n.cross(Vec3::UnitX()).normalized(), R0 = G + c * u;
  const Vec3 d = (R0 - P0).normalized();
  ModelBuilder b;
  b.set_spatial_gravity({0, 0, -9.81});
  b.spatial_body("crank", rod(0.3, a, P0 / 2, frame(Vec3::UnitX(), Vec3::UnitZ())));
  b.spatial_body("coupler", rod(0.6, (R0 - P0).norm(), (P0 + R0) / 2, frame(d, n)));
  b.spatial_body("rocker", rod(0.5, c, (G + R0) / 2, frame(u, n)));
  using K = SpatialJointKind;
  b.spatial_joint("bearing", K::kRevolute, "ground", "crank",
                  {.at = Vec3::Zero(), .axis = Vec3::UnitZ()});
  b.spatial_joint("pin", K::kSpherical, "crank", "coupler", {.at = P0});
  b.spatial_joint("wrist", K::kUniversal, "rocker", "coupler",
                  {.at = R0, .axis = n, .axis_b = d.cross(n).normalized()});
  b.spatial_joint("rocker_pivot", K::kRevolute, "ground", "rocker", {.at = G, .axis = n});
  b.joint_rotation_driver("motor", "bearing", std::make_shared<RampLaw>(0.0, omega, 0.25));
  b.joint_spring_damper("spring", "rocker_pivot", {.stiffness = 1.0});

  // 2. The study: 1.25 s at h = 2 ms; the motor's torque (its driver's multiplier) and its RMS
  //    over the second revolution.
  GeneralizedAlphaOptions ga;
  ga.t_end = 1.25;
  ga.h = 2e-3;
  std::unique_ptr<Model> model = b.build();
  const std::vector<int> motor_rows = b.joint_rows("motor");
  Study study(std::move(model), b.initial_state(), ga);
  study.add_measure(
      std::make_unique<ConstraintForceMeasure>("torque", motor_rows, std::vector<bool>{true}));
  study.add_response("rms_torque", "torque.0", ResponseSpec::Kind::kRms, 0.75, 1.25);
  auto design = std::make_unique<Design>();
  design->add_variable("k", 1.0, 0.0, 20.0);
  design->bind(b.parameter("spring.stiffness"), "k");
  study.set_design(std::move(design));

  // 3. Gradient at k = 1 N m/rad by the direct analytic method, and central differences.
  SensitivityOptions so;
  so.method = SensitivityOptions::Method::kDirectAnalytic;
  const auto eval = [&](double k, double* grad) {
    Vec p(1);
    p[0] = k;
    if (grad) {
      const SensitivityResult r = compute_sensitivities(study, p, so);
      if (!r.ok) throw std::runtime_error(r.message);
      *grad = r.responses[0].gradient(0, 0);
      return r.responses[0].values[0];
    }
    SensitivityCounts counts;
    return simulate_responses(study, p, counts)[0].values[0];
  };
  double g0 = 0;
  const double f0 = eval(1.0, &g0), delta = 1e-4;
  const double fd = (eval(1.0 + delta, nullptr) - eval(1.0 - delta, nullptr)) / (2 * delta);
  const double rel = std::abs(g0 - fd) / std::abs(fd);
  std::printf(
      "k = 1 N m/rad: RMS torque %.6f N m, gradient %.6e (central differences %.6e, "
      "rel. diff %.1e)\n",
      f0, g0, fd, rel);
  bool ok = rel < 1e-5;

  // 4. The stiffness where dJ/dk = 0: secant iterations on the exact gradient.
  double k0 = 1.0, k1 = 4.0, gk0 = g0, gk1 = 0, f1 = eval(k1, &gk1);
  for (int it = 0; it < 20 && std::abs(gk1) > 1e-6 * std::abs(g0); ++it) {
    const double k2 = std::clamp(k1 - gk1 * (k1 - k0) / (gk1 - gk0), 0.0, 20.0);
    k0 = k1, gk0 = gk1, k1 = k2;
    f1 = eval(k1, &gk1);
    std::printf("  k = %.6f N m/rad: RMS torque %.6f N m, gradient %.3e\n", k1, f1, gk1);
  }
  const double f_none = eval(0.0, nullptr);  // no spring
  const bool stationary = std::abs(gk1) < 1e-4 * std::abs(g0), lower = f1 < f_none && f1 < f0;
  std::printf(
      "optimum k = %.5f N m/rad: RMS torque %.6f N m (%+.1f %% against no spring, "
      "%.6f N m)\n",
      k1, f1, 100 * (f1 / f_none - 1), f_none);
  ok = ok && stationary && lower && k1 > 0 && k1 < 20;
  std::printf("%s\n", ok ? "checks passed" : "CHECK FAILED");
  return ok ? 0 : 1;
}
