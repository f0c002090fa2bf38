#pragma once
// Building blocks of the spatial tests: a rigid body in natural coordinates with its frame
// constraints, a zero state, an observer of the output grid, and a generalized-α run of a built
// model that calls back at every grid point.
#include <gtest/gtest.h>

#include <array>
#include <memory>
#include <string>

#include "lsmbs/integrators/generalized_alpha.hpp"
#include "lsmbs/integrators/initial_state.hpp"
#include "lsmbs/mbs/model.hpp"
#include "lsmbs/mbs/model_builder.hpp"
#include "lsmbs/mbs/spatial.hpp"

namespace lsmbs::checks {

// A spatial rigid body `name` in natural coordinates (mass m, principal moments I, gravity g on
// its centre of mass) with its six frame constraints, registered with the model (its placement
// left at the origin: the tests write their states); returns its first DOF.
inline int add_body(Model& model, const std::string& name, double m, const Vec3& I, const Vec3& g) {
  const int mp = model.add_parameter(name + ".mass", m);
  const std::array<int, 3> ip = {model.add_parameter(name + ".I1", I[0]),
                                 model.add_parameter(name + ".I2", I[1]),
                                 model.add_parameter(name + ".I3", I[2])};
  SpatialRigidBody b;
  b.name = name;
  b.mass_param = mp;
  b.inertia_params = ip;
  const int d0 = model.add_spatial_body(b).dof0;
  model.add_force(std::make_unique<SpatialRigidInertia>(d0, mp, ip, g, name));
  model.add_constraint(
      std::make_unique<SpatialFrameConstraint>(d0, SpatialFrameConstraint::Kind::kNormal));
  model.add_constraint(
      std::make_unique<SpatialFrameConstraint>(d0, SpatialFrameConstraint::Kind::kOrthogonal));
  return d0;
}

inline State zero_state(const Model& model) {
  State s;
  s.q = Vec::Zero(model.nq());
  s.v = Vec::Zero(model.nq());
  s.a = Vec::Zero(model.nq());
  s.lambda = Vec::Zero(model.nc());
  return s;
}

// Calls record() with the initial state and every converged state on the output grid.
struct GridRecorder : StepObserver {
  virtual void record(const State& s) = 0;
  void on_start(const State& s0, const Vec&, const AlphaCoefficients&, double, double,
                const SparseLU*) override {
    record(s0);
  }
  bool on_step(const StepInfo& info) override {
    if (info.grid_point) record(*info.state);
    return true;
  }
};

// Runs generalized-α (step h to t_end) from the builder's initial state projected onto the
// constraints (consistent), calling f at every grid point.
template <class F>
IntegratorSummary integrate(ModelBuilder& b, const Model& model, double h, double t_end, F f) {
  State s0 = b.initial_state();
  SparseLU lu;
  lu.analyze(model.pattern());
  const Status st =
      project_initial_state(model, model.params(), s0, lu, 1e-13, nullptr, &b.held_velocities());
  EXPECT_TRUE(st.ok()) << st.message;
  struct Obs : GridRecorder {
    F* f = nullptr;
    void record(const State& s) override { (*f)(s); }
  } obs;
  obs.f = &f;
  GeneralizedAlphaOptions o;
  o.h = h;
  o.t_end = t_end;
  return GeneralizedAlpha(o).run(model, model.params(), s0, {&obs});
}

}  // namespace lsmbs::checks
