// The library's uniform contracts (docs/architecture.md): every run result satisfies RunResult
// (status(), report()), every Options struct has validate() naming the offending field, the
// sensitivity methods sit behind one interface, and compare_gradients computes the documented
// norms. The references are hand-computed values and the field names of the structs.
#include <gtest/gtest.h>

#include <cmath>
#include <typeinfo>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/status.hpp"
#include "lsmbs/geometry/design_map.hpp"
#include "lsmbs/integrators/generalized_alpha.hpp"
#include "lsmbs/integrators/idas_ggl.hpp"
#include "lsmbs/integrators/static_solver.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/mbs/model_builder.hpp"
#include "lsmbs/optimization/mma_classic.hpp"
#include "lsmbs/optimization/optimizer.hpp"
#include "lsmbs/runs/bench.hpp"
#include "lsmbs/runs/geometry.hpp"
#include "lsmbs/runs/simulate.hpp"
#include "lsmbs/runs/verify.hpp"
#include "lsmbs/sensitivity/direct_observer.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/method.hpp"

namespace lsmbs {
namespace {

static_assert(RunResult<IntegratorSummary>);
static_assert(RunResult<IdasStats>);
static_assert(RunResult<StaticResult>);
static_assert(RunResult<SensitivityResult>);
static_assert(RunResult<GradientCheckResult>);
static_assert(RunResult<OptimizeResult>);
static_assert(RunResult<SimulationResult>);

bool starts_with(const std::string& s, const std::string& p) { return s.rfind(p, 0) == 0; }

// Every options struct: the defaults are valid, and each invalid field is named first.
template <class O, class F>
void expect_invalid(const std::string& field, F mutate) {
  O o;
  EXPECT_EQ(o.validate(), "") << typeid(O).name() << " defaults";
  mutate(o);
  const std::string msg = o.validate();
  EXPECT_TRUE(starts_with(msg, field + ":"))
      << typeid(O).name() << ": '" << msg << "' should name " << field;
}

TEST(Contracts, EveryOptionsValidateNamesTheField) {
  expect_invalid<GeneralizedAlphaOptions>("h", [](auto& o) { o.h = -1; });
  expect_invalid<GeneralizedAlphaOptions>("rho_inf", [](auto& o) { o.rho_inf = 2; });
  expect_invalid<IdasOptions>("rtol", [](auto& o) { o.rtol = 0; });
  expect_invalid<StaticOptions>("max_iter", [](auto& o) { o.max_iter = -1; });
  expect_invalid<StepObserverOptions>("threads", [](auto& o) { o.threads = 3; });
  expect_invalid<SensitivityOptions>("delta", [](auto& o) {
    o.method = SensitivityOptions::Method::kSemiAnalytical;
    o.delta = 0;
  });
  expect_invalid<SensitivityOptions>("threads", [](auto& o) { o.threads = 0; });
  expect_invalid<SensitivityOptions>("delta", [](auto& o) {
    o.method = SensitivityOptions::Method::kFdCentral;
    o.delta = NAN;
  });
  expect_invalid<GradientCheckOptions>("delta", [](auto& o) { o.delta = 2; });
  expect_invalid<GradientCheckOptions>("fail", [](auto& o) { o.fail = o.warn / 2; });
  expect_invalid<BackSolveOptions>("max_refinement", [](auto& o) { o.max_refinement = -1; });
  expect_invalid<MappingOptions>("mu_min", [](auto& o) { o.mu_min = 0; });
  expect_invalid<MappingOptions>("subgrid", [](auto& o) { o.subgrid = 0; });
  expect_invalid<MmaOptions>("move", [](auto& o) { o.move = 0; });
  expect_invalid<OptimizeOptions>("stop_after", [](auto& o) { o.stop_after = 0; });
  expect_invalid<RunOptions>("idas_options.atol", [](auto& o) {
    o.idas = true;
    o.idas_options.atol = -1;
  });
  expect_invalid<GeometryRunOptions>("image_width", [](auto& o) { o.image_width = 1; });
  expect_invalid<VerifyOptions>("tol_fd", [](auto& o) { o.tol_fd = 0; });
  expect_invalid<BenchOptions>("repetitions", [](auto& o) { o.repetitions = 0; });
  // the model builder's option structs (defaults of a flexible body are not valid: E, ρ and the
  // thickness have no sensible default)
  expect_invalid<RigidBodyOptions>("inertia", [](auto& o) { o.inertia = -1; });
  expect_invalid<SpringOptions>("free_length", [](auto& o) { o.free_length = -0.1; });
  expect_invalid<RotationalSpringOptions>("damping", [](auto& o) { o.damping = NAN; });
  expect_invalid<PrismaticOptions>("through", [](auto& o) { o.through = Vec2(INFINITY, 0); });
  FlexibleBodyOptions f;
  EXPECT_TRUE(starts_with(f.validate(), "material/E:")) << f.validate();
  f.E = 70e9;
  f.rho = 2700;
  f.thickness = 1e-3;
  EXPECT_EQ(f.validate(), "");
  f.nu = 0.5;
  EXPECT_TRUE(starts_with(f.validate(), "material/nu:")) << f.validate();
}

TEST(Contracts, RunStatusAndReportFollowTheFields) {
  IntegratorSummary s;
  s.steps = 1234;
  s.newton_iterations = 2468;
  s.t_reached = 0.5;
  EXPECT_EQ(s.status(), RunStatus::kComplete);
  EXPECT_NE(s.report().find("complete"), std::string::npos);
  EXPECT_NE(s.report().find("1234 steps"), std::string::npos) << s.report();
  EXPECT_NE(s.report().find("2468 Newton iterations"), std::string::npos) << s.report();
  s.ok = false;
  s.message = "Newton did not converge at t = 0.5 s";
  EXPECT_EQ(s.status(), RunStatus::kFailed);
  EXPECT_NE(s.report().find(s.message), std::string::npos);
  s.aborted = true;
  EXPECT_EQ(s.status(), RunStatus::kInterrupted);

  SensitivityResult r;
  r.counts.back_solves = 77;
  EXPECT_EQ(r.status(), RunStatus::kComplete);
  EXPECT_NE(r.report().find("77 back-solves"), std::string::npos) << r.report();
  r.ok = false;
  r.interrupted = true;
  EXPECT_EQ(r.status(), RunStatus::kInterrupted);

  OptimizeResult o;
  o.evaluations = 9;
  EXPECT_EQ(o.status(), RunStatus::kComplete);
  EXPECT_NE(o.report().find("9 evaluations"), std::string::npos) << o.report();
  o.failure = "evaluation 9: simulation failed";
  EXPECT_EQ(o.status(), RunStatus::kFailed);
  EXPECT_STREQ(run_status_name(RunStatus::kFailed), "failed");
}

TEST(Contracts, SensitivityMethodsSitBehindOneInterface) {
  using M = SensitivityOptions::Method;
  auto kind = [](M m) {
    SensitivityOptions o;
    o.method = m;
    const auto p = make_sensitivity_method(o);
    EXPECT_EQ(p->options().method, m);
    return std::string(typeid(*p).name());
  };
  const std::string direct = typeid(DirectSensitivity).name(),
                    fd = typeid(FiniteDifferenceSensitivity).name(),
                    idas = typeid(IdasSensitivity).name();
  EXPECT_EQ(kind(M::kSemiAnalytical), direct);
  EXPECT_EQ(kind(M::kSemiAnalyticalCentral), direct);
  EXPECT_EQ(kind(M::kDirectAnalytic), direct);
  EXPECT_EQ(kind(M::kFdForward), fd);
  EXPECT_EQ(kind(M::kFdCentral), fd);
  EXPECT_EQ(kind(M::kIdas), idas);
  EXPECT_EQ(kind(M::kIdasAdjoint), idas);
}

TEST(Contracts, InvalidSensitivityOptionsAreRefusedByName) {
  Case cs = load_case(std::string(LSMBS_SOURCE_DIR) +
                      "/data/slider_crank_rigid/slider_crank_spring.json");
  SensitivityOptions o;
  o.method = SensitivityOptions::Method::kSemiAnalytical;
  o.delta = -1;
  try {
    compute_sensitivities(cs, cs.design->initial(), o);
    FAIL() << "a negative delta was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("delta"), std::string::npos) << e.what();
  }
}

ResponseSensitivity response(const std::string& name, Mat g) {
  ResponseSensitivity r;
  r.name = name;
  r.values.assign(static_cast<size_t>(g.rows()), 0.0);
  r.gradient = std::move(g);
  return r;
}

TEST(Contracts, CompareGradientsComputesTheDocumentedNorms) {
  // response a: two values (steps) of two variables; response b: one value
  Mat ga(2, 2), ra(2, 2), gb(1, 2), rb(1, 2);
  ra << 10, -5, 0.1, 0.2;
  ga << 10.5, -5, 0.1, 0.3;  // row 0 off by 0.5 (‖ref row‖∞ 10), row 1 off by 0.1 (‖ref row‖∞ 0.2)
  rb << 2, 4;
  gb << 2, 4.2;  // off by 0.2, ‖ref‖∞ 4
  const std::vector<ResponseSensitivity> ref = {response("a", ra), response("b", rb)};
  const std::vector<ResponseSensitivity> got = {response("a", ga), response("b", gb)};
  const auto per_value = compare_gradients(got, ref, GradientNorm::kPerValue);
  EXPECT_NEAR(per_value.worst, 0.1 / 0.2, 1e-14);  // row 1 of a: 0.5
  EXPECT_EQ(per_value.where, "a[1]");
  const auto per_response = compare_gradients(got, ref, GradientNorm::kPerResponse);
  EXPECT_NEAR(per_response.worst, 0.5 / 10, 1e-14);  // a: max 0.5 / 10 = 0.05; b: 0.2 / 4 = 0.05
  const std::vector<ResponseSensitivity> wrong = {response("a", ga)};
  EXPECT_TRUE(std::isinf(compare_gradients(wrong, ref).worst));
  EXPECT_EQ(compare_gradients(ref, ref).worst, 0.0);
}

}  // namespace
}  // namespace lsmbs
