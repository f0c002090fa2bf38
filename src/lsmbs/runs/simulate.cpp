#include "lsmbs/runs/simulate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/text.hpp"
#include "lsmbs/io/initial_state_file.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/plot.hpp"
#include "lsmbs/records/json.hpp"
#include "lsmbs/sensitivity/response_quadrature.hpp"

namespace lsmbs {

std::vector<double> SimulationResult::column(const std::string& name) const {
  for (size_t c = 0; c < columns.size(); ++c)
    if (columns[c] == name) {
      std::vector<double> v;
      v.reserve(history.size());
      for (const auto& row : history) v.push_back(row[c]);
      return v;
    }
  throw Error("no measure column named '" + name + "'");
}

namespace {

class Recorder : public StepObserver {
 public:
  Recorder(const Case& cs, const ModelParams& params, SimulationResult& res, const RunOptions& ro)
      : cs_(cs), params_(params), res_(res), ro_(ro) {
    ncols_ = res.columns.size();
    for (const auto& m : cs.measures)
      if (const auto* sm = dynamic_cast<const StressMeasure*>(m.get()))
        stress_measures_.push_back(sm);
  }
  void on_start(const State& s0, const Vec&, const AlphaCoefficients&, double k, double,
                const SparseLU*) override {
    k_ = k;  // generalized-α's states carry λ/k (IDAS's, recorded by record_state, λ: k = 1)
    record(s0, 0);
  }
  void record_state(const State& s) {
    ++grid_;
    record(s, grid_);
  }
  bool on_step(const StepInfo& info) override {
    if (!info.grid_point) return true;
    ++grid_;
    record(*info.state, grid_);
    return true;
  }

 private:
  void record(const State& s, long step) {
    std::vector<double> row(ncols_);
    size_t c = 0;
    for (const auto& m : cs_.measures) {
      if (const auto* cf = dynamic_cast<const ConstraintForceMeasure*>(m.get()))
        cf->evaluate_scaled(*cs_.model, s, params_, k_, row.data() + c);
      else
        m->evaluate(*cs_.model, s, params_, row.data() + c);
      c += m->components().size();
    }
    res_.times.push_back(s.t);
    res_.history.push_back(std::move(row));
    // the largest relaxed element stress of each stress measure, and where it sits
    for (const StressMeasure* sm : stress_measures_) {
      sm->element_stresses(s, params_, stresses_);
      auto& mx = stress_max_[sm->name()];
      for (size_t e = 0; e < stresses_.size(); ++e)
        if (!(stresses_[e] <= mx.value)) mx = {stresses_[e], static_cast<int>(e), s.t};
    }
    if (!ro_.out_dir.empty() && cs_.output.vtu_stride > 0 && step % cs_.output.vtu_stride == 0) {
      const ModelVtkFiles f = write_model_vtk(ro_.out_dir, "vtu/", "_" + std::to_string(step),
                                              *cs_.model, params_, s.q, stress_measures_);
      for (const auto& [body, rel] : f.bodies) pvd_[body].emplace_back(s.t, rel);
      model_pvd_.emplace_back(s.t, f.multiblock);
    }
  }
  const Case& cs_;
  const ModelParams& params_;
  SimulationResult& res_;
  const RunOptions& ro_;
  size_t ncols_ = 0;
  double k_ = 1;  // the run's scaling of λ (ConstraintForceMeasure::evaluate_scaled)
  long grid_ = 0;
  std::vector<double> stresses_;
  std::vector<const StressMeasure*> stress_measures_;

 public:
  struct StressMax {
    double value = -1;
    int element = -1;
    double t = 0;
  };
  std::map<std::string, StressMax> stress_max_;
  std::map<std::string, std::vector<std::pair<double, std::string>>> pvd_;  // per body
  std::vector<std::pair<double, std::string>> model_pvd_;                   // the .vtm files
};

}  // namespace

std::string idas_tolerance_error(double rtol, double atol) {
  if (!(rtol > 0) || !std::isfinite(rtol) || rtol >= 1)
    return "rtol: expected a relative tolerance in (0, 1)";
  if (!(atol >= 0) || !std::isfinite(atol))
    return "atol: expected a non-negative absolute tolerance (0: rtol)";
  return {};
}

std::string RunOptions::validate() const {
  if (idas)
    if (auto msg = idas_options.validate(); !msg.empty()) return "idas_options." + msg;
  return {};
}

namespace {

// The model parameters of the run: the case's with the design point written in (the design is a
// value: the case is not changed), or the case's as they are.
ModelParams run_parameters(const Case& cs, const RunOptions& ro) {
  return cs.design && ro.design_point.size() ? parameters_at(cs, ro.design_point)
                                             : cs.model->params();
}

void integrate_idas(const Case& cs, const ModelParams& params, const RunOptions& ro, Recorder& rec,
                    SimulationResult& res) {
  IdasOptions io = ro.idas_options;
  io.h_out = cs.simulation.h;
  io.t_end = cs.simulation.t_end;
  IdasGGL idas(*cs.model, params, io);
  ResponseQuadrature quad(cs, {}, params, cs.initial.t, io.t_end);
  if (!quad.empty()) idas.set_quadrature(&quad);
  bool first = true;
  res.idas =
      idas.run(cs.initial, [&](const State& s, const Mat*, const Mat*, const Mat*, const Mat*) {
        if (first) {  // IDAS multipliers are physical: k = 1
          rec.on_start(s, s.a, AlphaCoefficients{}, 1.0, 0.0, nullptr);
          first = false;
        } else {
          rec.record_state(s);
        }
        if (ro.progress) ro.progress(Progress{"IDAS", s.t, io.t_end, 0, 0});
        res.final_state = s;
      });
  if (!res.idas.ok && interrupted()) res.interrupted = true;
  res.integrator.ok = res.idas.ok;
  res.integrator.message = res.idas.message;
  res.integrator.steps = res.idas.steps;
  res.integrator.residual_evaluations = res.idas.residual_evaluations;
  res.integrator.wall_seconds = res.idas.wall_seconds;
  res.integrator.t_reached = res.final_state.t;
  res.idas_options = io;
  if (!quad.empty()) res.quadratures = quad.results();
}

void integrate_alpha(const Case& cs, const ModelParams& params, const RunOptions& ro, Recorder& rec,
                     SimulationResult& res) {
  GeneralizedAlpha ga(cs.simulation);
  ProgressObserver prog(ro.progress, cs.simulation.t_end);
  InterruptObserver stop;
  res.integrator = ga.run(*cs.model, params, cs.initial, {&rec, &prog, &stop}, &res.final_state);
  if (res.integrator.aborted && interrupted()) {
    res.integrator.ok = false;
    res.interrupted = true;
    res.integrator.message = "interrupted (signal " + std::to_string(interrupted()) +
                             ") at t = " + std::to_string(res.integrator.t_reached) + " s";
  }
}

// The responses aggregated from the history (a run that did not reach t_end has none: its
// aggregates cover part of the run), as numbers and as summary.json's responses and
// response_definitions.
void aggregate_responses(const Case& cs, SimulationResult& res, nlohmann::json& responses,
                         nlohmann::json& windows) {
  for (const auto& r : cs.responses) {
    std::vector<double> v;
    v.reserve(res.history.size());
    for (const auto& row : res.history) v.push_back(row[r.column]);
    const Aggregate a = aggregate(r, res.times, v);
    const double val = a.scalar();
    const bool reached = res.integrator.ok;
    res.responses[r.name] = reached ? val : NAN;
    res.response_counts[r.name] = a.count;
    if (r.kind == ResponseSpec::Kind::kPerStep) {
      res.per_step[r.name] = a.values;
      res.per_step_times[r.name] = a.times;
      if (!reached) std::fill(res.per_step[r.name].begin(), res.per_step[r.name].end(), NAN);
      nlohmann::json arr = nlohmann::json::array();
      for (double x : res.per_step[r.name])
        arr.push_back(std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr));
      responses[r.name] = arr;
    } else {
      responses[r.name] =
          std::isfinite(val) && reached ? nlohmann::json(val) : nlohmann::json(nullptr);
    }
    windows[r.name] = {{"measure", res.columns[r.column]},
                       {"aggregate", ResponseSpec::kind_name(r.kind)},
                       {"window", r.window_text},
                       {"t0", r.t0 > -1e299 ? nlohmann::json(r.t0) : nlohmann::json(nullptr)},
                       {"t1", r.t1 < 1e299 ? nlohmann::json(r.t1) : nlohmann::json(nullptr)},
                       {"steps", a.count}};
  }
}

// summary.json["stress"]: the largest relaxed element stress of each stress measure, and where.
nlohmann::json stress_json(const Case& cs, const Recorder& rec) {
  nlohmann::json st = nlohmann::json::object();
  for (const auto& m : cs.measures)
    if (const auto* sm = dynamic_cast<const StressMeasure*>(m.get())) {
      const auto it = rec.stress_max_.find(sm->name());
      if (it == rec.stress_max_.end() || it->second.element < 0) continue;
      const auto& mx = it->second;
      const auto& o = sm->options();
      st[sm->name()] = {
          {"body", sm->body_name()},
          {"max_relaxed_von_mises", mx.value},
          {"unit", "Pa"},
          {"element", mx.element},
          {"t", mx.t},
          {"element_centre_body_frame", sm->element_centre(mx.element)},
          {"aggregate", o.aggregation == StressMeasure::Aggregation::kKs ? "ks" : "pnorm"},
          {"parameter", o.parameter},
          {"reference", o.reference},
          {"relaxation", o.relaxation},
          {"definition",
           "s_e = mu_e^relaxation * von Mises of the Cauchy stress at the element centre "
           "(solid material); the maximum over elements and recorded steps"}};
    }
  return st;
}

nlohmann::json summary_of(const Case& cs, const RunOptions& ro, const ModelParams& params,
                          const SimulationResult& res) {
  const Model& m = *cs.model;
  nlohmann::json bodies = nlohmann::json::array();
  for (const auto& b : m.flexible_bodies())
    bodies.push_back({{"name", b->name},
                      {"nodes", b->mesh.num_nodes()},
                      {"elements", b->mesh.num_elements()},
                      {"mass", b->mass(params)}});
  nlohmann::json S = case_provenance(ro.command_line.empty() ? "simulate" : ro.command_line, cs);
  S["overrides"] = cs.overrides;
  S["case_name"] = cs.name;
  S["status"] = res.integrator.ok ? "complete" : "partial";
  if (!res.integrator.ok) S["failure"] = res.integrator.message;
  if (res.interrupted) S["reason"] = "interrupted";
  S["options"] = {
      {"integrator", ro.idas ? "idas" : "generalized-alpha"},
      {ro.idas ? "idas" : "generalized_alpha",
       ro.idas ? nlohmann::json(res.idas_options) : nlohmann::json(cs.simulation)},
      {"output", {{"csv_stride", cs.output.csv_stride}, {"vtu_stride", cs.output.vtu_stride}}}};
  if (cs.design) S["design"] = design_json(cs, ro.design_point);
  S["model"] = {{"dofs", m.nq()},
                {"constraints", m.nc()},
                {"unknowns", m.n()},
                {"nonzeros", m.pattern().nnz()},
                {"rigid_bodies", m.rigid_bodies().size()},
                {"flexible_bodies", bodies}};
  S["counts"] = ro.idas ? nlohmann::json(res.idas) : nlohmann::json(res.integrator);
  std::vector<std::string> warnings = res.integrator.warnings();
  if (cs.design)  // a level-set feature off its body has no effect on this run
    if (auto w = cs.design->features_outside(ro.design_point.size() ? ro.design_point
                                                                    : cs.design->initial());
        !w.empty())
      warnings.push_back(w);
  if (!warnings.empty()) S["warnings"] = warnings;
  if (!res.quadratures.empty()) S["quadratures"] = quadratures_json(res.quadratures, {});
  S["wall_seconds"] = res.integrator.wall_seconds;
  S["units"] = units_json(cs);
  return S;
}

// history.png: one panel per measure, its columns in it (layout: io/plot.hpp). False: not drawn.
bool plot_history(const Case& cs, const std::string& png,
                  const std::vector<std::vector<double>>& rows) {
  PanelPlotSpec ps;
  ps.png = png;
  ps.title = cs.name + ": measured histories";
  ps.xlabel = "t [s]";
  int col = 2;
  for (const auto& m : cs.measures) {
    const auto comps = m->components();
    const auto units = m->units();
    Panel p;
    p.ylabel = m->name();
    if (std::all_of(units.begin(), units.end(), [&](const auto& u) { return u == units[0]; }))
      p.ylabel += " [" + units[0] + "]";
    for (size_t k = 0; k < comps.size(); ++k)
      p.series.push_back({col++, comps[k] + " [" + units[k] + "]"});
    ps.panels.push_back(std::move(p));
  }
  return !ps.panels.empty() && rows.size() >= 2 && plot_panels(ps, rows);
}

// The rows of history.csv: every csv_stride-th recorded step, and the last one whatever the
// stride.
std::vector<std::vector<double>> history_rows(const Case& cs, const SimulationResult& res) {
  std::vector<std::vector<double>> rows;
  auto add_row = [&](size_t i) {
    std::vector<double> r = {res.times[i]};
    r.insert(r.end(), res.history[i].begin(), res.history[i].end());
    rows.push_back(std::move(r));
  };
  const size_t stride = static_cast<size_t>(cs.output.csv_stride);
  for (size_t i = 0; i < res.history.size(); i += stride) add_row(i);
  if (!res.history.empty() && (res.history.size() - 1) % stride != 0)
    add_row(res.history.size() - 1);
  return rows;
}

// history.csv, final_state.json, history.png, the PVD series and summary.json. Ctrl-C while a
// finished run's outputs are written (a history of hundreds of MB takes seconds) ends the writing:
// what was written is listed, the run flagged interrupted. After an interrupted run the flag is
// already set: its outputs are written whole.
void write_outputs(const Case& cs, const RunOptions& ro, const Recorder& rec,
                   SimulationResult& res) {
  nlohmann::json& S = res.summary;
  std::vector<std::string> header = {"t"};
  header.insert(header.end(), res.columns.begin(), res.columns.end());
  const auto rows = history_rows(cs, res);
  const bool after_stop = interrupted() != 0;
  signal_point("write-outputs");
  auto poll = [&] {
    if (!after_stop) throw_if_interrupted("while the outputs were written");
  };
  write_csv(ro.out_dir + "/history.csv", header, rows, poll);
  poll();
  std::vector<std::string> files = {"history.csv", "summary.json"};
  // the state reached, for a later run to start from ("initial_state": {"from": ...})
  if (res.final_state.q.size() == cs.model->nq() && res.final_state.v.size() == cs.model->nq()) {
    write_json_atomic(
        ro.out_dir + "/final_state.json",
        final_state_json(*cs.model, res.final_state, cs.name,
                         res.integrator.ok && !res.interrupted ? "complete" : "partial",
                         "simulate"));
    files.push_back("final_state.json");
  }
  if (!cs.measures.empty() && rows.size() >= 2) {
    poll();
    const bool drawn = plot_history(cs, ro.out_dir + "/history.png", rows);
    if (drawn) files.push_back("history.png");
    S["history_plot"] =
        drawn ? "history.png" : "not drawn: no time range to draw (history.csv has the data)";
  }
  poll();
  const auto stems = body_file_stems(*cs.model);
  for (const auto& [body, entries] : rec.pvd_) {
    const std::string pvd = stems.at(body) + ".pvd";
    write_pvd(ro.out_dir + "/" + pvd, entries);
    files.push_back(pvd);
    for (const auto& e : entries) files.push_back(e.second);
  }
  if (!rec.model_pvd_.empty()) {
    write_pvd(ro.out_dir + "/" + kModelVtk + ".pvd", rec.model_pvd_);
    files.push_back(std::string(kModelVtk) + ".pvd");
    for (const auto& e : rec.model_pvd_) files.push_back(e.second);
  }
  S["files"] = file_list(std::move(files));
  write_json_atomic(ro.out_dir + "/summary.json", S);
}

}  // namespace

namespace {

// The responses of every condition's run, gathered and combined (sensitivity/conditions.hpp:
// "<condition>.<response>", state-independent ones once, the combinations).
std::vector<ResponseSensitivity> gathered(const Conditions& c,
                                          const std::vector<SimulationResult>& runs) {
  std::vector<SensitivityResult> as(runs.size());
  for (size_t k = 0; k < runs.size(); ++k) {
    as[k].ok = runs[k].integrator.ok;
    for (const auto& r : c.studies[k]->responses) {
      ResponseSensitivity x;
      x.name = r.name;
      const auto ps = runs[k].per_step.find(r.name);
      if (ps != runs[k].per_step.end()) {
        x.values = ps->second;
        x.times = runs[k].per_step_times.at(r.name);
      } else {
        x.values = {runs[k].responses.at(r.name)};
      }
      as[k].responses.push_back(std::move(x));
    }
  }
  return gather(c, as);
}

// Each condition in OUT/conditions/<stem>/ (its own summary.json, history, VTU), the top
// summary.json listing them with the gathered responses.
SimulationResult simulate_conditions(const Case& cs, const RunOptions& ro) {
  const Conditions c = conditions_of(cs);
  std::vector<std::string> stems;
  for (const auto& k : cs.conditions) {
    std::string stem = file_stem(k.name), base = stem;
    for (int i = 2; std::find(stems.begin(), stems.end(), stem) != stems.end(); ++i)
      stem = base + "_" + std::to_string(i);
    stems.push_back(stem);
  }
  std::vector<SimulationResult> runs(cs.conditions.size());
  ConditionTasks t;
  t.n = static_cast<int>(runs.size());
  t.cost = conditions_of(cs).costs();
  t.run = [&](int k) {
    RunOptions o = ro;
    if (!ro.out_dir.empty()) o.out_dir = ro.out_dir + "/conditions/" + stems[k];
    o.progress = nullptr;  // several runs at once: no progress line
    runs[k] = run_simulation(*cs.conditions[k].cs, o);
  };
  thread_executor(static_cast<int>(std::thread::hardware_concurrency()))(t);
  SimulationResult res;
  bool all = true;
  nlohmann::json responses = nlohmann::json::object(), conds = nlohmann::json::array();
  for (size_t k = 0; k < runs.size(); ++k) {
    all = all && runs[k].integrator.ok;
    res.interrupted = res.interrupted || runs[k].interrupted;
    conds.push_back({{"name", cs.conditions[k].name},
                     {"folder", "conditions/" + stems[k]},
                     {"status", runs[k].summary.value("status", "")}});
  }
  res.integrator = runs.front().integrator;
  res.integrator.ok = all;
  for (const auto& x : gathered(c, runs)) {  // a per-step response: its largest value
    res.responses[x.name] = all ? *std::max_element(x.values.begin(), x.values.end()) : NAN;
    if (!x.times.empty()) res.per_step[x.name] = x.values, res.per_step_times[x.name] = x.times;
    responses[x.name] = x.times.empty() ? nlohmann::json(x.values[0]) : nlohmann::json(x.values);
  }
  nlohmann::json& S = res.summary;
  S = case_provenance(ro.command_line.empty() ? "simulate" : ro.command_line, cs);
  S["overrides"] = cs.overrides;
  S["case_name"] = cs.name;
  S["status"] = res.interrupted ? "interrupted" : all ? "complete" : "partial";
  S["responses"] = responses;
  S["units"] = units_json(c);
  S["conditions"] = conditions_json(cs, c);
  S["conditions"]["runs"] = conds;
  if (cs.design) S["design"] = design_json(cs, ro.design_point);
  for (size_t k = 0; k < runs.size(); ++k)
    res.conditions.emplace_back(cs.conditions[k].name, std::move(runs[k]));
  if (!ro.out_dir.empty()) {
    std::vector<std::string> files = {"summary.json"};
    for (const auto& st : stems) files.push_back("conditions/" + st + "/");
    S["files"] = file_list(std::move(files));
    write_json_atomic(ro.out_dir + "/summary.json", S);
  }
  return res;
}

}  // namespace

SimulationResult run_simulation(const Case& cs, const RunOptions& ro) {
  if (!cs.conditions.empty()) return simulate_conditions(cs, ro);
  // the options of IDAS are checked by IDAS (a run that refuses them reports which, not ok)
  SimulationResult res;
  res.columns = cs.measure_columns();
  if (!ro.out_dir.empty()) {
    std::filesystem::create_directories(ro.out_dir);
    // an earlier run's summary must never stand next to this run's files
    std::error_code ec;
    std::filesystem::remove(ro.out_dir + "/summary.json", ec);
    if (cs.output.vtu_stride > 0) std::filesystem::create_directories(ro.out_dir + "/vtu");
  }
  const ModelParams params = run_parameters(cs, ro);
  Recorder rec(cs, params, res, ro);
  if (ro.idas)
    integrate_idas(cs, params, ro, rec, res);
  else
    integrate_alpha(cs, params, ro, rec, res);
  nlohmann::json responses = nlohmann::json::object(), windows = nlohmann::json::object();
  aggregate_responses(cs, res, responses, windows);
  res.summary = summary_of(cs, ro, params, res);
  res.summary["responses"] = responses;
  res.summary["response_definitions"] = windows;
  if (!rec.stress_max_.empty()) res.summary["stress"] = stress_json(cs, rec);
  if (!ro.out_dir.empty()) write_outputs(cs, ro, rec, res);
  return res;
}

RunStatus SimulationResult::status() const {
  if (interrupted) return RunStatus::kInterrupted;
  return integrator.status();
}

std::string SimulationResult::report() const {
  std::string r = idas.steps > 0 ? idas.report() : integrator.report();
  char b[160];
  for (const auto& [name, v] : responses) {
    std::snprintf(b, sizeof b, "\n  %-28s %.10g", name.c_str(), v);
    r += b;
  }
  return r;
}

}  // namespace lsmbs
