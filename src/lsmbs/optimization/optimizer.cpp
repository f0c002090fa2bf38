#include "lsmbs/optimization/optimizer.hpp"

#include <nlopt.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "lsmbs/core/csv.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/optimization/mma_classic.hpp"

namespace lsmbs {

namespace {

struct Context {
  Context(DesignProblem& p, const OptimizeOptions& opt) : prob(p), o(opt) {}
  DesignProblem& prob;
  const OptimizeOptions& o;
  nlopt_opt opt = nullptr;
  Vec lower, range;
  double f0 = 1;
  std::vector<Evaluation>
      history;  ///< every distinct point of this optimization, replayed ones too
  std::set<std::vector<double>> seen;
  long new_sims = 0;
  bool interrupted = false;
  bool stop = false;    ///< set when the run must end (interrupted, failed simulation)
  std::string failure;  ///< the first failed evaluation (OptimizeResult::failure)
  std::string case_sha, spec_json;

  Vec to_p(const double* x) const {
    Vec p(lower.size());
    for (Eigen::Index i = 0; i < p.size(); ++i) p[i] = lower[i] + x[i] * range[i];
    return p;
  }
  const Evaluation& eval(const double* x) {
    const Vec p = to_p(x);
    const long before = prob.simulations();
    const std::vector<double> key(p.data(), p.data() + p.size());
    // A point the optimizer has not visited in this run, whether simulated now or replayed from a
    // checkpoint: the history of a resumed run is the uninterrupted run's, from evaluation 1.
    const bool known = !seen.insert(key).second;
    const Evaluation& e = prob.evaluate(p);
    if (e.interrupted) {  // the evaluation in progress is dropped; the checkpoint has the ones
                          // before
      interrupted = true;
      request_stop();
      return e;
    }
    if (!known) {
      history.push_back(e);
      if (prob.simulations() > before) {
        ++new_sims;
        checkpoint();
      }
      if (o.on_evaluation) o.on_evaluation(static_cast<int>(history.size()), e);
      if ((o.stop_after >= 0 && new_sims >= o.stop_after) || lsmbs::interrupted()) {
        interrupted = true;
        request_stop();
      }
    }
    if (!e.ok) {
      if (failure.empty()) {
        std::ostringstream os;
        os << "evaluation " << history.size() << " at p = [";
        for (Eigen::Index i = 0; i < p.size(); ++i) os << (i ? ", " : "") << p[i];
        os << "] failed: " << e.message;
        failure = os.str();
      }
      request_stop();
    }
    return e;
  }
  void request_stop() {
    stop = true;
    if (opt) nlopt_force_stop(opt);
  }
  // scaled quantities (x in [0, 1]^n, f / f0, (g − ū)/|ū|)
  Vec scaled_objective_gradient(const Evaluation& e) const {
    return e.objective_gradient.cwiseProduct(range) / f0;
  }
  void scaled_constraints(const Evaluation& e, Vec& g, Mat& dg) const {
    const Eigen::Index m = static_cast<Eigen::Index>(e.constraints.size());
    g.resize(m);
    dg.resize(m, range.size());
    for (Eigen::Index j = 0; j < m; ++j) {
      const double s = static_cast<size_t>(j) < e.scale.size()
                           ? e.scale[j]
                           : std::max(std::abs(e.upper[j]), 1e-300);
      g[j] = (e.constraints[j] - e.upper[j]) / s;
      dg.row(j) = e.constraint_gradient.row(j).cwiseProduct(range.transpose()) / s;
    }
  }
  void checkpoint() {
    if (o.out_dir.empty() || !o.write_files) return;
    nlohmann::json ev = nlohmann::json::array();
    for (const auto& h : history) ev.push_back(evaluation_to_json(h));
    write_json_atomic(o.out_dir + "/checkpoint.json",
                      {{"case_sha256", case_sha}, {"spec", spec_json}, {"evaluations", ev}});
    write_history(o.out_dir + "/history.csv", prob, history);
  }
};

double objective_cb(unsigned n, const double* x, double* grad, void* data) {
  auto& c = *static_cast<Context*>(data);
  const Evaluation& e = c.eval(x);
  if (grad) Eigen::Map<Vec>(grad, n) = c.scaled_objective_gradient(e);
  return e.objective / c.f0;
}

void constraints_cb(unsigned m, double* result, unsigned n, const double* x, double* grad,
                    void* data) {
  auto& c = *static_cast<Context*>(data);
  const Evaluation& e = c.eval(x);
  Vec g;
  Mat dg;
  c.scaled_constraints(e, g, dg);
  Eigen::Map<Vec>(result, m) = g;
  if (grad)  // NLopt: row-major m × n
    for (unsigned j = 0; j < m; ++j)
      for (unsigned i = 0; i < n; ++i) grad[j * n + i] = dg(j, i);
}

const char* stop_word(nlopt_result r) {
  switch (r) {
    case NLOPT_SUCCESS:
      return "success";
    case NLOPT_STOPVAL_REACHED:
      return "stopval";
    case NLOPT_FTOL_REACHED:
      return "ftol";
    case NLOPT_XTOL_REACHED:
      return "xtol";
    case NLOPT_MAXEVAL_REACHED:
      return "max_evaluations";
    case NLOPT_MAXTIME_REACHED:
      return "max_time";
    case NLOPT_ROUNDOFF_LIMITED:
      return "roundoff_limited";
    case NLOPT_FORCED_STOP:
      return "stopped";
    default:
      return "nlopt_failure";
  }
}

std::string number(const char* f, double v) {
  char b[48];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// Max and min aggregates take one step's value: where the step moves between two designs the
// response has a kink, its gradient jumps, and the optimizer's model of it is wrong on one side.
// One sentence per such response of the problem, naming the first move.
std::vector<std::string> extreme_switches(const std::vector<Evaluation>& h) {
  std::map<std::string, std::pair<int, std::string>> moves;  // name → (count, first move)
  for (size_t k = 1; k < h.size(); ++k)
    for (const auto& [name, t] : h[k].extreme_times) {
      const auto prev = h[k - 1].extreme_times.find(name);
      if (prev == h[k - 1].extreme_times.end() || prev->second == t) continue;
      auto& m = moves[name];
      if (m.first++ == 0)
        m.second = "from t = " + number("%.6g", prev->second) + " s to t = " + number("%.6g", t) +
                   " s at evaluation " + std::to_string(k + 1);
    }
  std::vector<std::string> w;
  for (const auto& [name, m] : moves)
    w.push_back("response '" + name +
                "' is a maximum or minimum over time whose extreme step moved " +
                std::to_string(m.first) + " time(s) in " + std::to_string(h.size()) +
                " evaluations (first " + m.second +
                "): the response has a kink there and its gradient jumps, so the optimizer may "
                "stop at the kink rather than at an optimum; a KS aggregate (\"aggregate\": "
                "\"ks\") is a smooth upper bound of the maximum");
  return w;
}

std::vector<std::string> result_warnings(const DesignProblem& prob, const OptimizeResult& res) {
  std::vector<std::string> w;
  const auto& spec = prob.spec();
  if (res.final.ok && res.final.max_violation > spec.tol_constraint)
    w.push_back("the final design is infeasible: max relative constraint violation " +
                number("%.3e", res.final.max_violation) + " > " +
                number("%.3e", spec.tol_constraint) + " (relative_constraint_violation) after " +
                std::to_string(res.evaluations) + " evaluations");
  if (res.kkt && !res.kkt->satisfied())
    w.push_back("the final design is not a first-order (KKT) point: stationarity " +
                number("%.3g", res.kkt->stationarity) + ", wrong-signed gradients at bounds " +
                number("%.3g", res.kkt->bound_sign_violation) + " (relative to the objective's " +
                "largest scaled gradient; kkt_tolerance " + number("%.3g", spec.kkt_tolerance) +
                "); the optimizer stopped on '" + res.stop_reason +
                "'. Run on (a smaller relative_objective_change, more max_evaluations) or read "
                "the design as a point on the way");
  for (auto& s : extreme_switches(res.history)) w.push_back(std::move(s));
  return w;
}

const char* status_text(nlopt_result r) {
  switch (r) {
    case NLOPT_SUCCESS:
      return "success";
    case NLOPT_STOPVAL_REACHED:
      return "stopval reached";
    case NLOPT_FTOL_REACHED:
      return "relative objective change below tol_objective";
    case NLOPT_XTOL_REACHED:
      return "relative design change below tolerance";
    case NLOPT_MAXEVAL_REACHED:
      return "maximum number of evaluations reached";
    case NLOPT_MAXTIME_REACHED:
      return "maximum time reached";
    case NLOPT_FAILURE:
      return "NLopt failure";
    case NLOPT_INVALID_ARGS:
      return "invalid arguments";
    case NLOPT_OUT_OF_MEMORY:
      return "out of memory";
    case NLOPT_ROUNDOFF_LIMITED:
      return "round-off limited";
    case NLOPT_FORCED_STOP:
      return "stopped";
    default:
      return "unknown";
  }
}

// Svanberg's classic MMA: one simulation per outer iteration; stops when the objective changes
// by less than tol_objective (relative) between two iterations and the new design is feasible
// within tol_constraint (the paper's rule), or after max_evaluations simulations.
nlopt_result run_mma_classic(Context& c, std::vector<double>& xs, const Evaluation& e0) {
  const int n = static_cast<int>(xs.size());
  const auto& spec = c.prob.spec();
  MmaOptions mo;
  mo.move = spec.move_limit;
  mo.asyinit = spec.asymptote_init;
  MmaClassic mma(Vec::Zero(n), Vec::Ones(n), static_cast<int>(e0.constraints.size()), mo);
  Vec x = Eigen::Map<const Vec>(xs.data(), n);
  Evaluation cur = e0;
  for (int k = 1; k < spec.max_evaluations; ++k) {
    Vec g;
    Mat dg;
    c.scaled_constraints(cur, g, dg);
    const Vec xn = mma.step(x, c.scaled_objective_gradient(cur), g, dg).cwiseMax(0.0).cwiseMin(1.0);
    const Evaluation& e = c.eval(xn.data());
    if (c.stop) return NLOPT_FORCED_STOP;
    const double change =
        std::abs(e.objective - cur.objective) / std::max(std::abs(cur.objective), 1e-300);
    x = xn;
    cur = e;
    std::copy(x.data(), x.data() + n, xs.begin());
    if (change < spec.tol_objective && e.max_violation <= spec.tol_constraint)
      return NLOPT_FTOL_REACHED;
  }
  return NLOPT_MAXEVAL_REACHED;
}

}  // namespace

void write_history(const std::string& path, const DesignProblem& problem,
                   const std::vector<Evaluation>& h) {
  const auto& d = *problem.study().design;
  const Vec range = d.upper() - d.lower();
  // the gradient's norm with respect to the variables scaled to [0, 1] (the optimizer's): in the
  // unit of the response whatever the variables' units
  auto scaled_norm = [&](const Vec& g) {
    return g.size() == range.size() ? g.cwiseProduct(range).norm() : NAN;
  };
  std::string os = "evaluation,objective,max_constraint_violation,feasible,wall_seconds";
  for (const auto& v : d.variables) os += "," + csv_field(v.name);
  os += ",objective_gradient_norm";
  for (const auto& c : problem.constraint_names())
    os += "," + csv_field("constraint." + c) + "," + csv_field("constraint." + c + ".upper") + "," +
          csv_field("constraint." + c + ".gradient_norm");
  os += "\n";
  const size_t m = problem.constraint_names().size();
  for (size_t k = 0; k < h.size(); ++k) {
    const Evaluation& e = h[k];
    os += std::to_string(k + 1) + "," + csv_number(e.objective) + "," +
          csv_number(e.max_violation) + "," +
          (e.max_violation <= problem.spec().tol_constraint ? "1" : "0") + "," +
          csv_number(e.wall_seconds);
    for (Eigen::Index i = 0; i < e.p.size(); ++i) os += "," + csv_number(e.p[i]);
    os += "," + csv_number(scaled_norm(e.objective_gradient));
    for (size_t j = 0; j < m; ++j) {
      const bool has = j < e.constraints.size() && j < e.upper.size() &&
                       static_cast<Eigen::Index>(j) < e.constraint_gradient.rows();
      os +=
          "," + csv_number(has ? e.constraints[j] : NAN) + "," +
          csv_number(j < e.upper.size() ? e.upper[j] : NAN) + "," +
          csv_number(
              has ? scaled_norm(e.constraint_gradient.row(static_cast<Eigen::Index>(j)).transpose())
                  : NAN);
    }
    os += "\n";
  }
  write_file_atomic(path, os);
}

std::string OptimizeOptions::validate() const {
  if (stop_after != -1 && stop_after < 1)
    return "stop_after: expected -1 (never) or a positive number of simulations";
  if (resume && out_dir.empty()) return "resume: needs out_dir (the folder of the checkpoint)";
  if (!initial.allFinite()) return "initial: expected finite values";
  return {};
}

OptimizeResult optimize(DesignProblem& prob, const OptimizeOptions& o) {
  if (auto msg = o.validate(); !msg.empty()) throw Error("optimize option " + msg);
  const std::string& name = prob.spec().optimizer;
  if (name != "mma" && name != "ccsaq" && name != "slsqp" && name != "mma-svanberg")
    throw SetupError("optimization.optimizer", "unknown optimizer '" + name +
                                                   "': expected mma, ccsaq, slsqp or mma-svanberg");
  const auto t0 = std::chrono::steady_clock::now();
  const Study& cs = prob.study();
  const Design& d = *cs.design;
  const int n = d.size(), m = prob.num_constraints();
  Context c(prob, o);
  c.lower = d.lower();
  c.range = d.upper() - d.lower();
  c.case_sha = o.input_sha256;
  // the options that decide the optimizer's path (a checkpoint of other ones is refused): all but
  // the verdict's tolerance, which a resumed run may change
  nlohmann::json path_spec = prob.spec().to_json();
  path_spec.erase("kkt_tolerance");
  c.spec_json = path_spec.dump();

  if (o.resume) {
    const std::string path = o.out_dir + "/checkpoint.json";
    std::ifstream f(path);
    if (!f) throw Error(path, "", "cannot resume: no checkpoint");
    std::stringstream text;
    text << f.rdbuf();
    check_json_depth(text.str(), path);
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(text.str());
    } catch (const std::exception& e) {
      throw Error(path, "", std::string("cannot resume: damaged checkpoint (") + e.what() + ")");
    }
    if (!j.is_object())
      throw Error(path, "/", "cannot resume: damaged checkpoint (expected an object)");
    if (!j.contains("case_sha256") || j["case_sha256"] != o.input_sha256)
      throw Error(
          path, "/case_sha256",
          "cannot resume: the case changed since the checkpoint was written (its file, its --set "
          "overrides, or from Python its options or parameters)");
    if (!j.contains("spec") || j["spec"] != c.spec_json)
      throw Error(
          path, "/spec",
          "cannot resume: the optimization options changed since the checkpoint was written");
    if (!j.contains("evaluations") || !j["evaluations"].is_array())
      throw Error(path, "/evaluations",
                  "cannot resume: damaged checkpoint (expected an array of evaluations)");
    // every evaluation must fit this case (a hand-edited or damaged file could index out of range)
    const Eigen::Index nc = prob.num_constraints();
    for (size_t k = 0; k < j["evaluations"].size(); ++k) {
      Evaluation e;
      try {
        e = evaluation_from_json(j["evaluations"][k]);
      } catch (const std::exception& ex) {
        throw Error(path, "/evaluations/" + std::to_string(k),
                    std::string("cannot resume: damaged checkpoint (") + ex.what() + ")");
      }
      const bool sizes = e.p.size() == n && e.objective_gradient.size() == n &&
                         e.constraint_gradient.rows() == nc &&
                         e.constraint_gradient.cols() == (nc ? n : e.constraint_gradient.cols()) &&
                         static_cast<Eigen::Index>(e.upper.size()) ==
                             static_cast<Eigen::Index>(e.constraints.size()) &&
                         e.scale.size() == e.upper.size() &&
                         static_cast<Eigen::Index>(e.constraints.size()) <= nc;
      if (!sizes)
        throw Error(
            path, "/evaluations/" + std::to_string(k),
            "cannot resume: damaged checkpoint (the evaluation's sizes do not match the case)");
      prob.seed(e);
    }
  }

  const bool classic = prob.spec().optimizer == "mma-svanberg";
  nlopt_algorithm alg = prob.spec().optimizer == "ccsaq"   ? NLOPT_LD_CCSAQ
                        : prob.spec().optimizer == "slsqp" ? NLOPT_LD_SLSQP
                                                           : NLOPT_LD_MMA;
  std::vector<double> lb(n, 0.0), ub(n, 1.0), x(n);
  const Vec p0 = o.initial.size() ? o.initial : d.initial();
  for (int i = 0; i < n; ++i) x[i] = (p0[i] - c.lower[i]) / c.range[i];
  // objective scale from the initial design (evaluated first, also as the optimizer's first point)
  const Evaluation e0 = c.eval(x.data());
  OptimizeResult res;
  c.f0 = std::max(std::abs(e0.objective), 1e-300);
  nlopt_result r;
  if (!e0.ok && !e0.interrupted) {  // the initial design cannot be simulated: nothing to optimize
                                    // (c.failure says why)
    c.failure = "the initial design could not be simulated: " + c.failure;
    r = NLOPT_FORCED_STOP;
  } else if (classic) {
    r = c.stop ? NLOPT_FORCED_STOP : run_mma_classic(c, x, e0);
  } else {
    c.opt = nlopt_create(alg, n);
    nlopt_set_lower_bounds(c.opt, lb.data());
    nlopt_set_upper_bounds(c.opt, ub.data());
    nlopt_set_min_objective(c.opt, objective_cb, &c);
    if (m > 0) {
      std::vector<double> tol(m, 0.0);
      nlopt_add_inequality_mconstraint(c.opt, m, constraints_cb, &c, tol.data());
    }
    nlopt_set_ftol_rel(c.opt, prob.spec().tol_objective);
    nlopt_set_maxeval(c.opt, prob.spec().max_evaluations);
    if (prob.spec().inner_max_evaluations > 0 && alg != NLOPT_LD_SLSQP)
      nlopt_set_param(c.opt, "inner_maxeval", prob.spec().inner_max_evaluations);
    double fmin = 0;
    r = c.stop ? NLOPT_FORCED_STOP : nlopt_optimize(c.opt, x.data(), &fmin);
    nlopt_destroy(c.opt);
  }

  res.nlopt_code = r;
  res.nlopt_status = status_text(r);
  res.interrupted = c.interrupted;
  res.failure = c.failure;
  res.history = c.history;
  res.evaluations = static_cast<long>(c.history.size());
  res.simulations = prob.simulations();
  // final design: the best feasible evaluation (NLopt returns its best point too)
  int best = -1;
  for (size_t k = 0; k < c.history.size(); ++k)
    if (c.history[k].ok && c.history[k].max_violation <= prob.spec().tol_constraint &&
        (best < 0 || c.history[k].objective < c.history[best].objective))
      best = static_cast<int>(k);
  if (best >= 0) {
    res.final = c.history[best];
  } else if (c.interrupted &&
             lsmbs::interrupted()) {  // no simulation after Ctrl-C: NLopt's last point, unevaluated
    res.final.p = c.to_p(x.data());
    res.final.ok = false;
    res.final.interrupted = true;
    res.final.objective = res.final.max_violation = NAN;
    res.final.message = "interrupted before a feasible design was evaluated";
  } else {
    res.final = prob.evaluate(c.to_p(x.data()));
  }
  res.p = res.final.p;
  res.stop_reason = !c.failure.empty() ? "failed" : c.interrupted ? "interrupted" : stop_word(r);
  if (res.final.ok && res.final.objective_gradient.size() == n)
    res.kkt = kkt_report(prob, res.final, 1e-2, 1e-6, c.f0);  // scaled as the optimizer scales
  res.converged = !c.interrupted && c.failure.empty() && best >= 0 &&
                  (r == NLOPT_FTOL_REACHED || r == NLOPT_XTOL_REACHED || r == NLOPT_SUCCESS) &&
                  res.kkt && res.kkt->satisfied();
  res.warnings = result_warnings(prob, res);
  if (!o.out_dir.empty() && o.write_files)
    write_history(o.out_dir + "/history.csv", prob, c.history);
  res.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

RunStatus OptimizeResult::status() const {
  if (!failure.empty()) return RunStatus::kFailed;
  return interrupted ? RunStatus::kInterrupted : RunStatus::kComplete;
}

std::string OptimizeResult::report() const {
  char b[400], k[96] = "KKT not checked";
  if (kkt)
    std::snprintf(k, sizeof k, "KKT %s (stationarity %.3g)",
                  kkt->satisfied() ? "satisfied" : "not satisfied", kkt->stationarity);
  std::snprintf(
      b, sizeof b,
      "optimization: %s (%s): %ld evaluations, %ld simulations in this run, objective %.9g, max "
      "constraint violation %.3e, %s, %s, %.1f s",
      run_status_name(status()), nlopt_status.c_str(), evaluations, simulations, final.objective,
      final.max_violation, k, converged ? "converged" : "not converged", wall_seconds);
  return failure.empty() ? std::string(b) : std::string(b) + "\n  " + failure;
}

}  // namespace lsmbs
