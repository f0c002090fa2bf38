#include "lsmbs/sensitivity/conditions.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <numeric>
#include <thread>

#include "lsmbs/core/error.hpp"
#include "lsmbs/sensitivity/wire.hpp"

namespace lsmbs {

const char* ResponseCombination::kind_name(Kind k) {
  return k == Kind::kSum ? "sum" : k == Kind::kKs ? "ks" : "max";
}

double ResponseCombination::error_bound() const {
  return kind == Kind::kKs ? std::log(static_cast<double>(of.size())) / ks : 0.0;
}

Conditions Conditions::single(const Study& s) {
  Conditions c;
  c.names = {""};
  c.studies = {&s};
  return c;
}

namespace {

// The measure that records column `column` of a study's history.
const Measure* measure_of_column(const Study& s, int column) {
  int c = 0;
  for (const auto& m : s.measures) {
    if (!m) continue;
    const int n = static_cast<int>(m->components().size());
    if (column < c + n) return m.get();
    c += n;
  }
  return nullptr;
}

}  // namespace

bool Conditions::state_independent(const Study& s, size_t r) {
  const Measure* m = measure_of_column(s, s.responses[r].column);
  return m && m->state_independent() && s.responses[r].kind != ResponseSpec::Kind::kPerStep;
}

bool Conditions::reported(size_t k, size_t r) const {
  if (variant(k) || !state_independent(*studies[k], r)) return true;
  size_t first_plain = 0;
  while (first_plain < studies.size() && variant(first_plain)) ++first_plain;
  return k == first_plain;
}

std::string Conditions::response_name(size_t k, size_t r) const {
  const std::string& base = studies[k]->responses[r].name;
  if (names[k].empty() || (state_independent(*studies[k], r) && !variant(k))) return base;
  return names[k] + "." + base;
}

std::vector<std::string> Conditions::response_names() const {
  std::vector<std::string> v;
  for (size_t k = 0; k < studies.size(); ++k)
    for (size_t r = 0; r < studies[k]->responses.size(); ++r)
      if (reported(k, r)) v.push_back(response_name(k, r));
  for (const auto& c : combinations) v.push_back(c.name);
  return v;
}

std::string Conditions::unit(const std::string& name) const {
  for (size_t k = 0; k < studies.size(); ++k)
    for (size_t r = 0; r < studies[k]->responses.size(); ++r)
      if (reported(k, r) && response_name(k, r) == name) return studies[k]->response_unit(r);
  for (const auto& c : combinations)
    if (c.name == name && !c.of.empty()) return unit(c.of.front());
  return {};
}

void Conditions::validate() const {
  std::map<std::string, bool> known;  // name -> scalar
  for (size_t k = 0; k < studies.size(); ++k)
    for (size_t r = 0; r < studies[k]->responses.size(); ++r)
      if (reported(k, r))
        known[response_name(k, r)] = studies[k]->responses[r].kind != ResponseSpec::Kind::kPerStep;
  for (const auto& c : combinations) {
    auto fail = [&](const std::string& why) { throw SetupError("combined", why, c.name); };
    if (known.count(c.name)) fail("the name '" + c.name + "' is a response already");
    if (c.of.empty()) fail("\"of\": expected at least one response");
    std::string unit0;
    for (const auto& t : c.of) {
      const auto it = known.find(t);
      if (it == known.end()) {
        std::string all;
        for (const auto& [n, scalar] : known) all += (all.empty() ? "" : ", ") + n;
        fail("\"of\": unknown response '" + t + "' (responses: " + all + ")");
      }
      if (!it->second)
        fail("\"of\": '" + t + "' is a per-step response; combinations take scalar ones");
      const std::string u = unit(t);
      if (unit0.empty()) unit0 = u;
      if (u != unit0)
        fail("\"of\": '" + t + "' is in " + u + ", the terms before it in " + unit0 +
             ": a combination adds or compares quantities of one unit");
    }
    if (c.kind == ResponseCombination::Kind::kSum && !c.weights.empty() &&
        c.weights.size() != c.of.size())
      fail("\"weights\": expected one weight per response of \"of\" (" +
           std::to_string(c.of.size()) + ")");
    for (double w : c.weights)
      if (!std::isfinite(w)) fail("\"weights\": expected finite numbers");
    if (c.kind == ResponseCombination::Kind::kKs && !(c.ks > 0 && std::isfinite(c.ks)))
      fail("\"ks\": expected the KS parameter ρ > 0 (in 1 / the responses' unit)");
    known[c.name] = true;
  }
}

namespace {

// value and gradient (row 0) of the combination of `terms`
ResponseSensitivity combine(const ResponseCombination& c,
                            const std::vector<const ResponseSensitivity*>& terms) {
  ResponseSensitivity out;
  out.name = c.name;
  const Eigen::Index nv = terms.front()->gradient.cols();
  Eigen::RowVectorXd g = Eigen::RowVectorXd::Zero(nv);
  double value = 0;
  switch (c.kind) {
    case ResponseCombination::Kind::kSum:
      for (size_t i = 0; i < terms.size(); ++i) {
        const double w = c.weights.empty() ? 1.0 : c.weights[i];
        value += w * terms[i]->values[0];
        if (terms[i]->gradient.rows()) g += w * terms[i]->gradient.row(0);
      }
      break;
    case ResponseCombination::Kind::kMax: {
      size_t best = 0;
      for (size_t i = 1; i < terms.size(); ++i)
        if (terms[i]->values[0] > terms[best]->values[0]) best = i;
      value = terms[best]->values[0];
      if (terms[best]->gradient.rows()) g = terms[best]->gradient.row(0);
      break;
    }
    case ResponseCombination::Kind::kKs: {
      // KS = m + (1/ρ) ln Σ exp(ρ (r_i − m)), m = max r_i (no overflow); ∂KS = Σ w_i ∂r_i with the
      // weights w_i = exp(ρ (r_i − m)) / Σ exp(ρ (r_j − m))
      double m = terms.front()->values[0];
      for (const auto* t : terms) m = std::max(m, t->values[0]);
      double sum = 0;
      std::vector<double> e;
      for (const auto* t : terms) sum += e.emplace_back(std::exp(c.ks * (t->values[0] - m)));
      value = m + std::log(sum) / c.ks;
      for (size_t i = 0; i < terms.size(); ++i)
        if (terms[i]->gradient.rows()) g += (e[i] / sum) * terms[i]->gradient.row(0);
      break;
    }
  }
  out.values = {value};
  out.gradient = Mat(g);
  return out;
}

}  // namespace

std::vector<ResponseSensitivity> gather(const Conditions& c,
                                        const std::vector<SensitivityResult>& per_condition) {
  std::vector<ResponseSensitivity> out;
  std::map<std::string, size_t> at;
  for (size_t k = 0; k < c.size() && k < per_condition.size(); ++k) {
    const auto& res = per_condition[k];
    if (!res.ok) continue;
    for (size_t r = 0; r < res.responses.size() && r < c.studies[k]->responses.size(); ++r) {
      if (!c.reported(k, r)) continue;
      ResponseSensitivity x = res.responses[r];
      x.name = c.response_name(k, r);
      at[x.name] = out.size();
      out.push_back(std::move(x));
    }
  }
  for (const auto& comb : c.combinations) {
    std::vector<const ResponseSensitivity*> terms;
    for (const auto& t : comb.of)
      if (const auto it = at.find(t); it != at.end()) terms.push_back(&out[it->second]);
    if (terms.size() != comb.of.size()) continue;  // a term's condition failed
    ResponseSensitivity x = combine(comb, terms);
    at[x.name] = out.size();
    out.push_back(std::move(x));
  }
  return out;
}

std::vector<double> Conditions::costs() const {
  std::vector<double> c;
  for (const Study* s : studies) c.push_back(std::ceil(s->simulation.t_end / s->simulation.h));
  return c;
}

std::vector<int> costliest_first(const ConditionTasks& t) {
  std::vector<int> order(static_cast<size_t>(t.n));
  std::iota(order.begin(), order.end(), 0);
  if (t.cost.size() == static_cast<size_t>(t.n))
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return t.cost[static_cast<size_t>(a)] > t.cost[static_cast<size_t>(b)];
    });
  return order;
}

std::vector<int> assign_tasks(const ConditionTasks& t, int workers) {
  std::vector<int> owner(static_cast<size_t>(t.n));
  std::vector<double> load(static_cast<size_t>(std::max(1, workers)), 0.0);
  for (const int k : costliest_first(t)) {
    const auto w = static_cast<size_t>(std::min_element(load.begin(), load.end()) - load.begin());
    owner[static_cast<size_t>(k)] = static_cast<int>(w);
    load[w] += t.cost.size() == static_cast<size_t>(t.n) ? t.cost[static_cast<size_t>(k)] : 1.0;
  }
  return owner;
}

ConditionExecutor thread_executor(int threads) {
  return [threads](const ConditionTasks& t) {
    const int n = t.n;
    const int workers = std::max(1, std::min(threads, n));
    const std::vector<int> order = costliest_first(t);
    if (workers == 1) {
      for (int k = 0; k < n; ++k) t.run(k);
      return;
    }
    std::atomic<int> next{0};
    std::vector<std::thread> pool;
    std::exception_ptr error;
    std::mutex error_lock;
    for (int w = 0; w < workers; ++w)
      pool.emplace_back([&] {
        for (int i; (i = next++) < n;) try {
            t.run(order[static_cast<size_t>(i)]);
          } catch (...) {
            const std::lock_guard<std::mutex> lock(error_lock);
            if (!error) error = std::current_exception();
          }
      });
    for (auto& th : pool) th.join();
    if (error) std::rethrow_exception(error);
  };
}

std::vector<SensitivityResult> compute_conditions(const Conditions& c, const Vec& p,
                                                  const SensitivityOptions& o,
                                                  const ConditionExecutor& run) {
  std::vector<SensitivityResult> results(c.size());
  ConditionTasks t;
  t.n = static_cast<int>(c.size());
  t.cost = c.costs();
  t.run = [&](int k) {
    results[static_cast<size_t>(k)] = compute_sensitivities(*c.studies[k], p, o);
  };
  t.save = [&](int k) { return to_wire(results[static_cast<size_t>(k)]); };
  t.load = [&](int k, const std::string& b) {
    results[static_cast<size_t>(k)] = sensitivity_result_from_wire(b);
  };
  run(t);
  return results;
}

SensitivityResult compute_sensitivities(const Conditions& c, const Vec& p,
                                        const SensitivityOptions& o, const ConditionExecutor& run) {
  if (!c.several() && c.combinations.empty()) return compute_sensitivities(c.first(), p, o);
  const auto t0 = std::chrono::steady_clock::now();
  SensitivityResult r = merge(c, compute_conditions(c, p, o, run));
  r.counts.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

GradientCheckResult check_gradients(const Conditions& c, const Vec& p,
                                    const std::vector<ResponseSensitivity>& gradients,
                                    const GradientCheckOptions& o, const ConditionExecutor& run) {
  if (!c.first().design) throw SetupError("design", "a gradient check needs design variables");
  if (!c.several() && c.combinations.empty()) return check_gradients(c.first(), p, gradients, o);
  return check_gradients(
      *c.first().design, p, gradients, o, [&](const Vec& x, SensitivityCounts& counts) {
        std::vector<SensitivityResult> runs(c.size());
        ConditionTasks t;
        t.n = static_cast<int>(c.size());
        t.cost = c.costs();
        t.run = [&](int k) {
          SensitivityCounts each;
          runs[static_cast<size_t>(k)].responses = simulate_responses(*c.studies[k], x, each);
        };
        t.save = [&](int k) { return to_wire(runs[static_cast<size_t>(k)].responses); };
        t.load = [&](int k, const std::string& b) {
          runs[static_cast<size_t>(k)].responses = responses_from_wire(b);
        };
        run(t);
        counts.simulations += static_cast<long>(c.size());
        return gather(c, runs);
      });
}

SensitivityResult merge(const Conditions& c, const std::vector<SensitivityResult>& per_condition) {
  SensitivityResult out;
  out.responses = gather(c, per_condition);
  for (size_t k = 0; k < per_condition.size(); ++k) {
    const auto& r = per_condition[k];
    const std::string who = c.names[k].empty() ? "" : "condition '" + c.names[k] + "': ";
    if (!r.ok && out.ok) {
      out.ok = false;
      out.message = who + r.message;
    }
    out.interrupted = out.interrupted || r.interrupted;
    for (const auto& w : r.warnings) out.warnings.push_back(who + w);
    SensitivityCounts& s = out.counts;
    const SensitivityCounts& a = r.counts;
    s.simulations += a.simulations, s.steps += a.steps, s.newton_iterations += a.newton_iterations;
    s.factorizations += a.factorizations, s.residual_evaluations += a.residual_evaluations;
    s.pseudo_load_residuals += a.pseudo_load_residuals;
    s.element_pseudo_loads += a.element_pseudo_loads;
    s.mass_damping_products += a.mass_damping_products;
    s.back_solves += a.back_solves, s.back_solve_rhs += a.back_solve_rhs;
    s.sensitivity_matrix_assemblies += a.sensitivity_matrix_assemblies;
    s.refinement_solves += a.refinement_solves;
    s.sensitivity_factorizations += a.sensitivity_factorizations;
    s.predictor_matrix_steps += a.predictor_matrix_steps;
    s.wall_seconds = std::max(s.wall_seconds, a.wall_seconds);  // they may run at once
    s.primal_wall_seconds += a.primal_wall_seconds;
    s.adjoint_solves += a.adjoint_solves;
    s.adjoint_recomputed_steps += a.adjoint_recomputed_steps;
    s.adjoint_memory_bytes = std::max(s.adjoint_memory_bytes, a.adjoint_memory_bytes);
    for (auto q : r.quadratures) {
      if (!c.names[k].empty()) q.name = c.names[k] + "." + q.name;
      out.quadratures.push_back(std::move(q));
    }
  }
  if (!per_condition.empty()) {
    out.primal = per_condition.front().primal;
    out.idas = per_condition.front().idas;
  }
  return out;
}

}  // namespace lsmbs
