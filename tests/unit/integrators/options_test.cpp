// The options structs of the integrators: the defaults are valid, and each invalid value is
// refused by validate() with a message "field: what is expected" that names the field (the case
// loader maps the field to its JSON path); the runs refuse invalid options with that message.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "lsmbs/integrators/generalized_alpha.hpp"
#include "lsmbs/integrators/idas_ggl.hpp"
#include "lsmbs/integrators/static_solver.hpp"
#include "support/pendulum.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;

namespace {

template <class Options>
struct Breakage {
  std::string field;
  std::function<void(Options&)> make_invalid;
};

template <class Options>
void expect_each_field_named(const std::vector<Breakage<Options>>& cases) {
  for (const auto& c : cases) {
    Options o;
    c.make_invalid(o);
    const std::string msg = o.validate();
    EXPECT_EQ(msg.substr(0, c.field.size() + 2), c.field + ": ")
        << "for " << c.field << ", got \"" << msg << "\"";
  }
}

}  // namespace

TEST(IntegratorOptions, DefaultsAreValid) {
  EXPECT_EQ(GeneralizedAlphaOptions{}.validate(), "");
  EXPECT_EQ(StepObserverOptions{}.validate(), "");
  EXPECT_EQ(IdasOptions{}.validate(), "");
  EXPECT_EQ(IdasOptions::reference().validate(), "");
  EXPECT_EQ(StaticOptions{}.validate(), "");
}

TEST(IntegratorOptions, GeneralizedAlphaNamesTheOffendingField) {
  using O = GeneralizedAlphaOptions;
  expect_each_field_named<O>({{"h", [](O& o) { o.h = 0; }},
                              {"t_end", [](O& o) { o.t_end = -1; }},
                              {"rho_inf", [](O& o) { o.rho_inf = 1.5; }},
                              {"tol_r", [](O& o) { o.tol_r = NAN; }},
                              {"tol_phi", [](O& o) { o.tol_phi = 0; }},
                              {"tol_q", [](O& o) { o.tol_q = -1e-12; }},
                              {"force_floor", [](O& o) { o.force_floor = -1; }},
                              {"max_iter", [](O& o) { o.max_iter = 0; }},
                              {"min_iter", [](O& o) { o.min_iter = o.max_iter + 1; }},
                              {"max_halvings", [](O& o) { o.max_halvings = 31; }},
                              {"k", [](O& o) { o.k = -1; }},
                              {"zeta", [](O& o) { o.zeta = -1; }}});
}

TEST(IntegratorOptions, ObserverOptionsNameTheOffendingField) {
  using O = StepObserverOptions;
  expect_each_field_named<O>(
      {{"threads", [](O& o) { o.threads = 0; }}, {"threads", [](O& o) { o.threads = 3; }}});
}

TEST(IntegratorOptions, IdasNamesTheOffendingField) {
  using O = IdasOptions;
  expect_each_field_named<O>(
      {{"rtol", [](O& o) { o.rtol = 0; }},
       {"atol", [](O& o) { o.atol = -1; }},
       {"h_out", [](O& o) { o.h_out = 0; }},
       {"t_end", [](O& o) { o.t_end = NAN; }},
       {"max_steps", [](O& o) { o.max_steps = 0; }},
       {"max_order", [](O& o) { o.max_order = 6; }},
       {"max_order", [](O& o) { o.max_order = -1; }},
       {"klu_pivot_tolerance", [](O& o) { o.klu_pivot_tolerance = 0; }},
       {"klu_pivot_tolerance", [](O& o) { o.klu_pivot_tolerance = 1.5; }},
       {"adjoint_checkpoint_steps", [](O& o) { o.adjoint_checkpoint_steps = 0; }}});
}

TEST(IntegratorOptions, StaticNamesTheOffendingField) {
  using O = StaticOptions;
  expect_each_field_named<O>({{"t", [](O& o) { o.t = INFINITY; }},
                              {"tol_r", [](O& o) { o.tol_r = 0; }},
                              {"tol_phi", [](O& o) { o.tol_phi = NAN; }},
                              {"max_iter", [](O& o) { o.max_iter = -1; }},
                              {"k", [](O& o) { o.k = -2; }}});
}

TEST(IntegratorOptions, RunsRefuseInvalidOptionsWithTheFieldNamed) {
  Case cs = test::make_case(test::Pendulum{}.json(1e-2, 0.1));
  StepObserverOptions served;
  served.threads = 3;
  const auto r =
      GeneralizedAlpha(cs.simulation, served).run(*cs.model, cs.model->params(), cs.initial, {});
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("threads: expected 1 or 2"), std::string::npos) << r.message;
  EXPECT_EQ(r.steps, 0);

  GeneralizedAlphaOptions go = cs.simulation;
  go.rho_inf = -0.1;
  const auto g = GeneralizedAlpha(go).run(*cs.model, cs.model->params(), cs.initial, {});
  EXPECT_FALSE(g.ok);
  EXPECT_NE(g.message.find("rho_inf: "), std::string::npos) << g.message;

  StaticOptions so;
  so.tol_r = -1;
  State s = cs.initial;
  const auto st = solve_static(*cs.model, cs.model->params(), s, so);
  EXPECT_FALSE(st.ok);
  EXPECT_NE(st.message.find("tol_r: "), std::string::npos) << st.message;
}
