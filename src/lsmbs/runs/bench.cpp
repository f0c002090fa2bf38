#include "lsmbs/runs/bench.hpp"

#include <filesystem>

#include "lsmbs/core/clock.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/linalg/sparse_lu.hpp"
#include "lsmbs/mbs/linear_solver_setup.hpp"
#include "lsmbs/runs/simulate.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs {

std::string BenchOptions::validate() const {
  if (repetitions < 1) return "repetitions: expected at least 1";
  if (threads < 1 || threads > 2) return "threads: expected 1 or 2";
  return {};
}

namespace {

// The floor of one step at the initial state: one residual, one iteration matrix, one numeric
// factorization (KLU: a refactorization) and one solve, each timed over `repetitions`.
nlohmann::json floor_seconds(const Case& cs, const BenchOptions& o, SparseLU& lu, double& floor) {
  const Model& m = *cs.model;
  State s = cs.initial;
  s.v.conservativeResize(m.nq());
  s.a.setZero(m.nq());
  s.lambda.setZero(m.nc());
  const auto c = AlphaCoefficients::make(cs.simulation.rho_inf, cs.simulation.h);
  const double k = GeneralizedAlpha::automatic_scaling(m, m.params(), s, c);
  Vec R, x;
  std::vector<double> vals;
  analyze_model_matrix(lu, m, cs.simulation.linear_solver, cs.simulation.ordering);
  m.iteration_matrix(s, m.params(), {c.beta_p, c.gamma_p, 1}, k, k, vals);
  lu.factor(vals);
  const int n = o.repetitions;
  double t = now_seconds();
  for (int i = 0; i < n; ++i) m.residual(s, m.params(), k, k, R);
  const double t_res = (now_seconds() - t) / n;
  t = now_seconds();
  for (int i = 0; i < n; ++i)
    m.iteration_matrix(s, m.params(), {c.beta_p, c.gamma_p, 1}, k, k, vals);
  const double t_mat = (now_seconds() - t) / n;
  t = now_seconds();
  for (int i = 0; i < n; ++i) lu.factor(vals);
  const double t_factor = (now_seconds() - t) / n;
  const Vec ones = Vec::Ones(m.n());
  t = now_seconds();
  for (int i = 0; i < n; ++i) {
    x = ones;  // a fresh right-hand side: repeated solves of one vector would underflow to
               // denormals
    lu.solve(x);
  }
  const double t_solve = (now_seconds() - t) / n;
  const double t_lu = t_factor + t_solve;
  floor = t_res + t_mat + t_lu;
  return {{"residual", t_res}, {"iteration_matrix", t_mat}, {"factor", t_factor},
          {"solve", t_solve},  {"factor_and_solve", t_lu},  {"total", floor}};
}

// Per step, without the run's setup (symbolic analysis, projection, consistent start), split as
// the integrator timed it (IntegratorSummary::seconds).
nlohmann::json primal_json(const IntegratorSummary& primal, double t_primal, double floor) {
  const auto& ps = primal.seconds;
  const double steps = static_cast<double>(primal.steps);
  const double step = t_primal / steps;
  return {{"wall_seconds", t_primal},
          {"steps", primal.steps},
          {"newton_per_step", primal.newton_iterations / steps},
          {"factorizations_per_step", primal.factorizations / steps},
          {"linear_iterations_per_step", primal.linear_iterations / steps},
          {"max_linear_iterations", primal.max_linear_iterations},
          {"seconds_per_step", step},
          {"step_over_floor", step / floor},
          {"setup_seconds", ps.setup},
          {"stepping_seconds_per_step", (t_primal - ps.setup) / steps},
          {"per_step_seconds",
           {{"residual", ps.residual / steps},
            {"matrix", ps.matrix / steps},
            {"factor", ps.factor / steps},
            {"solve", ps.solve / steps}}}};
}

// Each sensitivity method at the initial design: the default matrix under the method's name, the
// others (direct methods) as "method/matrix".
nlohmann::json sensitivity_seconds(const Case& cs, const BenchOptions& o, double t_primal) {
  nlohmann::json sens = nlohmann::json::object();
  for (const auto& name : o.methods) {
    SensitivityOptions probe;
    SensitivityOptions::parse(name, probe.method);
    const bool direct = !probe.is_idas() &&
                        probe.method != SensitivityOptions::Method::kFdForward &&
                        probe.method != SensitivityOptions::Method::kFdCentral;
    std::vector<std::string> matrices = {SensitivityOptions::matrix_name(probe.matrix)};
    if (direct)
      for (const auto& m : o.matrices)
        if (m != matrices[0]) matrices.push_back(m);
    for (const auto& mx : matrices) {
      SensitivityOptions so = probe;
      SensitivityOptions::parse_matrix(mx, so.matrix);
      so.threads = o.threads;
      const double t = now_seconds();
      const auto r = compute_sensitivities(cs, cs.design->initial(), so);
      const double w = now_seconds() - t;
      sens[mx == matrices[0] ? name : name + "/" + mx] = {
          {"wall_seconds", w},
          {"over_primal", w / t_primal},
          {"ok", r.ok},
          {"variables", cs.design->size()},
          {"matrix", mx},
          {"factorizations", r.counts.factorizations},
          {"sensitivity_factorizations", r.counts.sensitivity_factorizations},
          {"refinement_solves", r.counts.refinement_solves},
          {"predictor_matrix_steps", r.counts.predictor_matrix_steps},
          {"steps", r.counts.steps}};
    }
  }
  return sens;
}

}  // namespace

nlohmann::json run_bench(const std::string& file, const BenchOptions& o) {
  if (auto msg = o.validate(); !msg.empty()) throw Error("bench option " + msg);
  const Case cs = load_case(file, o.overrides);
  for (const auto& m : o.methods) {
    SensitivityOptions::Method mm;
    if (!SensitivityOptions::parse(m, mm))
      throw Error("--methods: unknown sensitivity method '" + m + "'");
  }
  if (!o.methods.empty() && (!cs.design || cs.responses.empty()))
    throw Error(file, "/design",
                "sensitivity benchmarks need design variables and responses (or --methods none)");
  if (o.on_loaded) o.on_loaded(cs);
  std::filesystem::create_directories(o.out_dir);
  const Model& m = *cs.model;
  SparseLU lu;
  double floor = 0;
  const nlohmann::json floor_json = floor_seconds(cs, o, lu, floor);
  const double t = now_seconds();
  const auto primal = GeneralizedAlpha(cs.simulation).run(m, m.params(), cs.initial, {});
  const double t_primal = now_seconds() - t;
  if (!primal.ok) throw NumericalFailure("primal run failed: " + primal.message);
  nlohmann::json J = provenance(o.command_line, file, cs.sha256);
  if (!cs.input_files.empty()) J["input_files_sha256"] = cs.input_files;
  J["case_name"] = cs.name;
  J["status"] = "complete";
  J["model"] = {{"dofs", m.nq()},
                {"constraints", m.nc()},
                {"nonzeros", m.pattern().nnz()},
                {"ordering", SparseLU::ordering_name(lu.ordering())},
                {"linear_solver", SparseLU::solver_name(lu.solver_used())},
                {"lu_nonzeros", lu.factor_nonzeros()}};
  if (const BlockAmg* amg = lu.amg()) {  // the floor's solver: the AMG block and its shape
    const auto& c = amg->counters();
    J["model"]["amg_block"] = {{"unknowns", c.block_unknowns},
                               {"direct_unknowns", c.direct_unknowns},
                               {"element_layers", c.layers},
                               {"preconditioner", c.bulky ? "bulky" : "thin"}};
  }
  J["floor_seconds"] = floor_json;
  J["primal"] = primal_json(primal, t_primal, floor);
  J["sensitivities"] = sensitivity_seconds(cs, o, t_primal);
  J["peak_rss_kb"] = peak_rss_kb();
  J["options"] = {{"repetitions", o.repetitions},
                  {"methods", o.methods},
                  {"matrices", o.matrices},
                  {"threads", o.threads}};
  J["responses"] = nlohmann::json::object();
  J["files"] = file_list({"bench.json", "summary.json"});
  write_json_atomic(o.out_dir + "/bench.json", J);
  write_json_atomic(o.out_dir + "/summary.json", J);
  return J;
}

}  // namespace lsmbs
