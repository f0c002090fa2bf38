#include "lsmbs/io/optimization_spec.hpp"

#include "lsmbs/io/json_reader.hpp"

namespace lsmbs {

OptimizationSpec parse_optimization(const Case& cs) {
  if (cs.optimization.is_null())
    throw Error(cs.file, "/optimization", "the case has no optimization section");
  if (!cs.design)
    throw Error(cs.file, "/design", "optimization needs a design section (design variables)");
  const JsonReader r(cs.optimization, cs.file, "/optimization");
  if (!r.is_object()) r.fail("expected an object");
  OptimizationSpec s;
  // the responses of the case, or of its service conditions ("<condition>.<response>",
  // state-independent ones unprefixed) and the combined ones
  const Conditions conditions = conditions_of(cs);
  auto response = [&](const JsonReader& at, const std::string& key, bool scalar) {
    const std::string n = at.string(key);
    for (size_t k = 0; k < conditions.size(); ++k)
      for (size_t i = 0; i < conditions.studies[k]->responses.size(); ++i)
        if (conditions.reported(k, i) && conditions.response_name(k, i) == n) {
          if (scalar && conditions.studies[k]->responses[i].kind == ResponseSpec::Kind::kPerStep)
            at.fail(key, "the objective must be a scalar response");
          return n;
        }
    for (const auto& c : conditions.combinations)
      if (c.name == n) return n;
    std::string all;
    for (const auto& name : conditions.response_names()) all += (all.empty() ? "" : ", ") + name;
    at.fail(key, "unknown response '" + n + "' (" +
                     (conditions.several() ? "responses of the conditions: " + all
                                           : "define it in output.responses") +
                     ")");
  };
  s.objective = response(r, "objective", true);
  // a constraint bounds a response from above ("upper"), below ("lower"), both, or to a value
  // ("equals": both bounds at that value); each bound is one constraint g ≤ ū of the optimizer
  for (const auto& c : r.items("constraints")) {
    const std::string resp = response(c, "response", false);
    const bool has_up = c.has("upper"), has_lo = c.has("lower"), has_eq = c.has("equals");
    if (has_eq && (has_up || has_lo))
      c.fail("equals", "expected \"equals\" alone, or \"lower\" and/or \"upper\"");
    if (!has_eq && !has_up && !has_lo)
      c.fail("expected \"upper\", \"lower\", both, or \"equals\" (the bound of the response)");
    double scale = 0;
    if (c.has("scale")) scale = c.positive("scale");
    auto add = [&](const char* key, double bound, bool lower) {
      if (bound == 0 && scale == 0)
        c.fail(key,
               "a zero bound needs \"scale\": a reference value of the response (constraints "
               "are scaled by |bound|)");
      OptimizationSpec::Constraint k;
      k.response = resp;
      k.lower = lower;
      k.upper = lower ? -bound : bound;
      k.scale = scale;
      s.constraints.push_back(k);
    };
    if (has_eq) {
      const double v = c.number("equals");
      add("equals", v, false);
      add("equals", v, true);
    } else {
      const double lo = has_lo ? c.number("lower") : 0, up = has_up ? c.number("upper") : 0;
      if (has_lo && has_up && !(lo <= up)) c.fail("lower", "expected lower <= upper");
      if (has_up) add("upper", up, false);
      if (has_lo) add("lower", lo, true);
    }
    c.finish();
  }
  s.optimizer = r.one_of("optimizer", {"mma", "ccsaq", "slsqp", "mma-svanberg"}, "mma");
  if (r.has("move_limit")) {
    if (s.optimizer != "mma-svanberg")
      r.fail(
          "move_limit",
          "a move limit needs \"optimizer\": \"mma-svanberg\" (NLopt 2.7 cannot bound its steps)");
    s.move_limit = r.positive("move_limit");
    if (s.move_limit > 1)
      r.fail("move_limit", "expected a fraction of the variable range in (0, 1]");
  }
  if (r.has("asymptote_init")) {
    if (s.optimizer != "mma-svanberg")
      r.fail("asymptote_init", "the asymptotes are options of \"optimizer\": \"mma-svanberg\"");
    s.asymptote_init = r.positive("asymptote_init");
    if (s.asymptote_init > 1)
      r.fail("asymptote_init", "expected a fraction of the variable range in (0, 1]");
  }
  if (auto so = r.optional_child("sensitivity")) {
    const std::string m = so->string("method", "direct-analytic");
    if (!SensitivityOptions::parse(m, s.sensitivity.method)) {
      std::string all;
      for (const auto& n : SensitivityOptions::names()) all += (all.empty() ? "" : ", ") + n;
      so->fail("method", "expected one of " + all);
    }
    if (s.sensitivity.method == SensitivityOptions::Method::kIdasAdjoint)
      so->fail(
          "method",
          "idas-adjoint gives gradients of the time-integral quadratures only, not of the grid "
          "responses the optimizer uses; expected another method");
    s.sensitivity.delta = so->positive("delta", s.sensitivity.delta);
    s.sensitivity.relative =
        so->one_of("delta_mode", {"relative", "absolute"}, "relative") == "relative";
    if (!SensitivityOptions::parse_matrix(
            so->string("matrix", SensitivityOptions::matrix_name(SensitivityOptions{}.matrix)),
            s.sensitivity.matrix))
      so->fail("matrix", "expected last, converged or refined");
    s.sensitivity.threads = so->integer("threads", s.sensitivity.threads, 1);
    s.sensitivity.adjoint_memory_mb =
        so->non_negative("adjoint_memory_mb", s.sensitivity.adjoint_memory_mb);
    if (s.sensitivity.threads > 2) so->fail("threads", "expected 1 or 2");
    so->finish();
  }
  if (auto st = r.optional_child("stop")) {
    s.tol_objective = st->positive("relative_objective_change", s.tol_objective);
    s.tol_constraint = st->non_negative("relative_constraint_violation", s.tol_constraint);
    s.max_evaluations = st->integer("max_evaluations", s.max_evaluations, 1);
    st->finish();
  }
  if (auto j = r.optional_child("judge")) {
    s.judge.enabled = j->boolean("enabled", s.judge.enabled);
    s.judge.min_elements = j->positive("min_elements", s.judge.min_elements);
    s.judge.ersatz = j->boolean("ersatz", s.judge.ersatz);
    s.judge.ersatz_factor = j->positive("ersatz_factor", s.judge.ersatz_factor);
    if (s.judge.ersatz_factor >= 1)
      j->fail("ersatz_factor", "expected a factor in (0, 1) that makes μ_min smaller");
    s.judge.ersatz_tolerance = j->positive("ersatz_tolerance", s.judge.ersatz_tolerance);
    j->finish();
  }
  if (auto l = r.optional_child("length_scale")) {
    auto& L = s.length_scale;
    L.enabled = l->boolean("enabled", true);
    L.min_size = l->positive("min_size", L.min_size);
    L.min_ligament = l->non_negative("min_ligament", L.min_ligament);
    L.min_edge = l->non_negative("min_edge", L.min_edge);
    L.min_member = l->non_negative("min_member", L.min_member);
    L.no_cut = l->non_negative("no_cut", L.no_cut);
    L.tolerance = l->positive("tolerance", L.tolerance);
    if (L.tolerance >= 1) l->fail("tolerance", "expected a fraction of each bound in (0, 1)");
    l->finish();
  }
  s.inner_max_evaluations = r.integer("inner_max_evaluations", 0, 0);
  s.kkt_tolerance = r.positive("kkt_tolerance", s.kkt_tolerance);
  if (s.inner_max_evaluations > 0 && s.optimizer == "mma-svanberg")
    r.fail("inner_max_evaluations",
           "the classic MMA has no inner iterations (this option is for mma and ccsaq)");
  r.finish();
  return s;
}

void set_optimizer(OptimizationSpec& spec, const Case& cs, const std::string& optimizer,
                   const std::string& origin) {
  if (optimizer.empty()) return;
  // the words of optimize()'s own check, before anything runs (the gradient check)
  if (optimizer != "mma" && optimizer != "ccsaq" && optimizer != "slsqp" &&
      optimizer != "mma-svanberg")
    throw Error(
        cs.file, "/optimization/optimizer",
        "unknown optimizer '" + optimizer + "': expected mma, ccsaq, slsqp or mma-svanberg");
  if (optimizer != "mma-svanberg" && cs.optimization.contains("move_limit"))
    throw Error(origin + ": the case sets a move_limit, which only mma-svanberg has");
  spec.optimizer = optimizer;
}

}  // namespace lsmbs
