#include "lsmbs/runs/sweep.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <sstream>

#include "lsmbs/core/csv.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/records/json.hpp"
#include "lsmbs/runs/mpi.hpp"
#include "lsmbs/sensitivity/conditions.hpp"

namespace lsmbs {
namespace {

// What an axis sets: a design variable (its index), or a value of the document (its pointer).
struct Target {
  int variable = -1;
  std::string pointer;
};

Target target_of(const Case& cs, const nlohmann::json& doc, const SweepAxis& a) {
  if (cs.design)
    if (const int k = cs.design->variable_index(a.name); k >= 0) {
      const auto& v = cs.design->variables[static_cast<size_t>(k)];
      if (a.lower < v.lower || a.upper > v.upper) {
        char b[200];
        std::snprintf(b, sizeof b, "[%g, %g] leaves the bounds [%g, %g] of design variable '%s'",
                      a.lower, a.upper, v.lower, v.upper, a.name.c_str());
        throw Error("sweep axis " + a.name + ": " + b);
      }
      return {k, ""};
    }
  if (!a.name.empty() && a.name[0] == '/')
    return {-1, indexed_pointer(doc, a.name, "sweep axis " + a.name)};
  const int i = cs.model->parameter_index(a.name);
  if (i < 0) {
    std::string known;
    if (cs.design)
      for (const auto& v : cs.design->variables) known += (known.empty() ? "" : ", ") + v.name;
    throw Error("sweep axis '" + a.name + "': not a design variable (" +
                (known.empty() ? "none" : known) +
                "), a model parameter (lsmbs.Case.parameters) or a JSON pointer (/simulation/h)");
  }
  if (cs.design)
    for (const auto& b : cs.design->bindings)
      if (b.parameter == i)
        throw Error("sweep axis '" + a.name + "': design variable '" +
                    cs.design->variables[static_cast<size_t>(b.variable)].name +
                    "' sets this parameter; sweep the variable");
  const std::string path = parameter_json_path(cs, i);
  if (path.empty()) throw Error("sweep axis '" + a.name + "': the case does not say where it is");
  return {-1, path};
}

// The points: the grid of the axes (the last fastest) or a Latin hypercube.
std::vector<std::vector<double>> plan_points(const SweepOptions& o) {
  std::vector<std::vector<double>> pts;
  const size_t n = o.axes.size();
  if (o.samples > 0) {
    std::mt19937_64 gen(o.seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    pts.assign(static_cast<size_t>(o.samples), std::vector<double>(n));
    for (size_t a = 0; a < n; ++a) {
      std::vector<int> strata(static_cast<size_t>(o.samples));
      for (int i = 0; i < o.samples; ++i) strata[static_cast<size_t>(i)] = i;
      for (int i = o.samples - 1; i > 0; --i)  // Fisher–Yates with the seeded generator
        std::swap(strata[static_cast<size_t>(i)],
                  strata[static_cast<size_t>(gen() % static_cast<uint64_t>(i + 1))]);
      const auto& ax = o.axes[a];
      for (int i = 0; i < o.samples; ++i) {
        const double x = (strata[static_cast<size_t>(i)] + u(gen)) / o.samples;
        pts[static_cast<size_t>(i)][a] = ax.lower + x * (ax.upper - ax.lower);
      }
    }
    return pts;
  }
  pts.push_back({});
  for (const auto& ax : o.axes) {
    std::vector<std::vector<double>> next;
    for (const auto& p : pts)
      for (int i = 0; i < ax.points; ++i) {
        auto q = p;
        q.push_back(ax.points == 1 ? ax.lower
                                   : ax.lower + (ax.upper - ax.lower) * i / (ax.points - 1.0));
        next.push_back(std::move(q));
      }
    pts = std::move(next);
  }
  return pts;
}

struct Plan {
  std::vector<Target> targets;
  std::vector<std::vector<double>> points;
  std::vector<std::string> responses;  // scalar responses (gathered names)
  std::vector<std::string> variables;
  std::vector<std::string> columns;
  nlohmann::json doc;  // the case's document as it stands
};

Plan make_plan(const Case& cs, const SweepOptions& o) {
  Plan pl;
  pl.doc = current_document(cs);
  for (const auto& a : o.axes) pl.targets.push_back(target_of(cs, pl.doc, a));
  pl.points = plan_points(o);
  const Conditions c = conditions_of(cs);
  for (const auto& name : c.response_names()) {  // scalar ones: a CSV cell each
    bool per_step = false;
    for (size_t k = 0; k < c.size(); ++k)
      for (size_t r = 0; r < c.studies[k]->responses.size(); ++r)
        if (c.reported(k, r) && c.response_name(k, r) == name)
          per_step = c.studies[k]->responses[r].kind == ResponseSpec::Kind::kPerStep;
    if (!per_step) pl.responses.push_back(name);
  }
  if (cs.design)
    for (const auto& v : cs.design->variables) pl.variables.push_back(v.name);
  pl.columns = {"point", "status"};
  for (const auto& a : o.axes) pl.columns.push_back(a.name);
  for (const auto& r : pl.responses) pl.columns.push_back(r);
  if (o.gradients)
    for (const auto& r : pl.responses)
      for (const auto& v : pl.variables) pl.columns.push_back("d(" + r + ")/d(" + v + ")");
  pl.columns.push_back("wall_seconds");
  pl.columns.push_back("message");
  return pl;
}

// One point: its case (loaded anew when an axis sets a value of the document) evaluated at its
// design point; the row's numbers (NaN where a failed point gives none), its status and message.
nlohmann::json evaluate_point(const Case& cs, const SweepOptions& o, const Plan& pl, int k) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto& x = pl.points[static_cast<size_t>(k)];
  Vec p = cs.design ? cs.design->initial() : Vec();
  nlohmann::json doc = pl.doc;
  bool reload = false;
  for (size_t a = 0; a < x.size(); ++a) {
    if (pl.targets[a].variable >= 0) {
      p[pl.targets[a].variable] = x[a];
    } else {
      doc[nlohmann::json::json_pointer(pl.targets[a].pointer)] = x[a];
      reload = true;
    }
  }
  std::vector<double> values;
  std::string status = "complete", message;
  try {
    std::optional<Case> point;
    if (reload) point.emplace(load_case_json(doc, cs.file, cs.base_dir));
    const Case& at = reload ? *point : cs;
    const Conditions c = conditions_of(at);
    std::vector<ResponseSensitivity> got;
    if (o.gradients) {
      const auto r = compute_sensitivities(c, p, o.sensitivity, thread_executor(1));
      if (!r.ok) throw NumericalFailure(r.message);
      got = r.responses;
    } else {
      std::vector<SensitivityResult> runs(c.size());
      for (size_t i = 0; i < c.size(); ++i) {
        SensitivityCounts counts;
        runs[i].responses = simulate_responses(*c.studies[i], p, counts);
      }
      got = gather(c, runs);
    }
    auto find = [&](const std::string& n) -> const ResponseSensitivity* {
      for (const auto& r : got)
        if (r.name == n) return &r;
      return nullptr;
    };
    for (const auto& n : pl.responses) {
      const auto* r = find(n);
      values.push_back(r && !r->values.empty() ? r->values[0] : NAN);
    }
    if (o.gradients)
      for (const auto& n : pl.responses)
        for (size_t v = 0; v < pl.variables.size(); ++v) {
          const auto* r = find(n);
          values.push_back(r && r->gradient.rows() ? r->gradient(0, static_cast<Eigen::Index>(v))
                                                   : NAN);
        }
    if (interrupted()) status = "not run";  // stopped within: not a result of this point
  } catch (const std::exception& e) {
    status = interrupted() ? "not run" : "failed";
    message = e.what();
    values.assign(pl.responses.size() * (o.gradients ? 1 + pl.variables.size() : 1), NAN);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  nlohmann::json j = {{"status", status}, {"message", message}, {"wall", wall}};
  nlohmann::json v = nlohmann::json::array();
  for (double d : values) v.push_back(std::isnan(d) ? nlohmann::json(nullptr) : nlohmann::json(d));
  j["values"] = v;
  return j;
}

std::string csv_row(int k, const SweepOptions& o, const Plan& pl, const nlohmann::json& r) {
  std::string line = std::to_string(k) + "," + csv_field(r["status"].get<std::string>());
  for (double x : pl.points[static_cast<size_t>(k)]) line += "," + csv_number(x);
  for (const auto& v : r["values"]) line += "," + csv_number(v.is_null() ? NAN : v.get<double>());
  (void)o;
  line += "," + csv_number(r["wall"].get<double>());
  line += "," + csv_field(r["message"].get<std::string>()) + "\n";
  return line;
}

nlohmann::json plan_json(const SweepOptions& o) {
  nlohmann::json axes = nlohmann::json::array();
  for (const auto& a : o.axes)
    axes.push_back(
        {{"name", a.name}, {"lower", a.lower}, {"upper", a.upper}, {"points", a.points}});
  return {{"axes", axes},
          {"samples", o.samples},
          {"seed", o.seed},
          {"gradients", o.gradients},
          {"method", SensitivityOptions::name(o.sensitivity.method)}};
}

// Points an earlier run of this plan finished (sweep.csv rows complete or failed), by index.
std::vector<int> finished_points(const SweepOptions& o, const Plan& pl) {
  const std::string plan_file = o.out_dir + "/sweep.json";
  std::ifstream f(plan_file);
  if (!f) throw Error(plan_file + ": cannot resume a sweep: no sweep.json here");
  nlohmann::json stored;
  try {
    stored = nlohmann::json::parse(f);
  } catch (const std::exception& e) {
    throw Error(plan_file + ": unreadable (" + e.what() + ")");
  }
  if (stored.value("plan", nlohmann::json()) != plan_json(o))
    throw Error("resume: " + plan_file +
                " holds another sweep (axes, samples, seed, gradients or "
                "method); give the same options");
  std::vector<int> done;
  std::ifstream csv(o.out_dir + "/sweep.csv");
  std::string line;
  std::getline(csv, line);  // the header
  while (std::getline(csv, line)) {
    const auto comma = line.find(',');
    if (comma == std::string::npos) continue;
    const int k = std::atoi(line.substr(0, comma).c_str());
    const std::string rest = line.substr(comma + 1);
    if (k >= 0 && k < static_cast<int>(pl.points.size()) &&
        (rest.rfind("complete,", 0) == 0 || rest.rfind("failed,", 0) == 0))
      done.push_back(k);
  }
  return done;
}

// Rank 0 of a sweep that writes: sweep.json (the plan), and sweep.csv anew with its header and
// the rows of the points an earlier run finished (resume); those rows.
std::map<int, std::string> start_files(const SweepOptions& o, const Plan& pl,
                                       const std::vector<int>& done_before,
                                       const std::string& header) {
  std::map<int, std::string> lines;
  std::filesystem::create_directories(o.out_dir);
  write_json_atomic(o.out_dir + "/sweep.json",
                    {{"plan", plan_json(o)}, {"points", pl.points}, {"columns", pl.columns}});
  if (o.resume) {  // the earlier run's finished rows stay
    std::ifstream csv(o.out_dir + "/sweep.csv");
    std::string line;
    std::getline(csv, line);
    while (std::getline(csv, line)) {
      const int k = std::atoi(line.substr(0, line.find(',')).c_str());
      if (std::find(done_before.begin(), done_before.end(), k) != done_before.end())
        lines[k] = line + "\n";
    }
  }
  std::string text = header;
  for (const auto& [k, l] : lines) text += l;
  write_file_atomic(o.out_dir + "/sweep.csv", text);
  return lines;
}

// summary.json of a sweep: provenance, status, options, counts of the points, columns, units.
nlohmann::json sweep_summary(const Case& cs, const SweepOptions& o, const Plan& pl,
                             const SweepRun& run) {
  const auto n = static_cast<int>(pl.points.size());
  nlohmann::json S = case_provenance(o.command, cs);
  S["overrides"] = cs.overrides;
  S["case_name"] = cs.name;
  S["status"] = run.interrupted ? "interrupted" : run.failed ? "partial" : "complete";
  S["options"] = {{"sweep", plan_json(o)},
                  {"jobs", o.jobs},
                  {"ranks", mpi::world().size},
                  {"sensitivity", nlohmann::json(o.sensitivity)}};
  S["points"] = {{"total", n},
                 {"completed", run.completed},
                 {"failed", run.failed},
                 {"finished_before", run.skipped},
                 {"not_run", n - run.completed - run.failed - run.skipped}};
  S["columns"] = pl.columns;
  S["responses"] = nlohmann::json::object();
  S["units"] = units_json(conditions_of(cs));
  return S;
}

}  // namespace

std::string SweepOptions::validate() const {
  if (axes.empty()) return "axes: expected at least one quantity to sweep";
  for (const auto& a : axes) {
    if (!(std::isfinite(a.lower) && std::isfinite(a.upper) && a.upper >= a.lower))
      return "axes: " + a.name + ": expected finite bounds with lower <= upper";
    if (samples == 0 && a.points < 1) return "axes: " + a.name + ": expected at least 1 point";
  }
  if (samples < 0) return "samples: expected 0 (a grid) or a number of Latin-hypercube points";
  if (jobs < 1) return "jobs: expected at least 1";
  if (resume && out_dir.empty()) return "resume: needs out_dir (the sweep's folder)";
  return {};
}

int SweepRun::exit_code() const {
  if (ranks_exit >= 0) return ranks_exit;
  if (interrupted) return 130;
  return failed > 0 ? 1 : 0;
}

SweepRun run_sweep(const Case& cs, const SweepOptions& o) {
  if (auto msg = o.validate(); !msg.empty()) throw Error("sweep option " + msg);
  const Plan pl = make_plan(cs, o);
  if (pl.points.size() > 1000000) throw Error("sweep: more than 1e6 points; sweep fewer");
  SweepRun run;
  run.columns = pl.columns;
  run.points = pl.points;
  const size_t n = pl.points.size();
  run.rows.assign(n, {});
  run.wall.assign(n, NAN);
  run.status.assign(n, "not run");
  run.message.assign(n, "");
  const bool writes = !o.out_dir.empty() && mpi::world().rank == 0;
  std::vector<int> todo, done_before;
  if (o.resume && mpi::world().rank == 0) done_before = finished_points(o, pl);
  done_before = [&] {  // every rank skips the same points
    nlohmann::json j = done_before;
    return nlohmann::json::parse(mpi::broadcast(j.dump())).get<std::vector<int>>();
  }();
  for (int k = 0; k < static_cast<int>(n); ++k)
    if (std::find(done_before.begin(), done_before.end(), k) == done_before.end())
      todo.push_back(k);
  run.skipped = static_cast<int>(done_before.size());
  std::string header;
  for (size_t i = 0; i < pl.columns.size(); ++i)
    header += (i ? "," : "") + csv_field(pl.columns[i]);
  header += "\n";
  // every finished point's row (this run's and earlier ones')
  std::map<int, std::string> lines =
      writes ? start_files(o, pl, done_before, header) : std::map<int, std::string>{};
  std::ofstream appended;
  if (writes) appended.open(o.out_dir + "/sweep.csv", std::ios::app);
  auto record = [&](int k, const nlohmann::json& r) {
    const auto ku = static_cast<size_t>(k);
    run.status[ku] = r["status"];
    run.message[ku] = r["message"];
    if (run.status[ku] == "complete") ++run.completed;
    if (run.status[ku] == "failed") ++run.failed;
    for (const auto& v : r["values"]) run.rows[ku].push_back(v.is_null() ? NAN : v.get<double>());
    run.wall[ku] = r["wall"].is_null() ? NAN : r["wall"].get<double>();
    if (run.status[ku] == "not run") return;  // left for a resume
    const std::string line = csv_row(k, o, pl, r);
    lines[k] = line;
    if (appended) appended << line << std::flush;  // written as it finishes
    if (o.on_message)
      o.on_message("sweep: point " + std::to_string(k) + " " + run.status[ku] + " (" +
                   std::to_string(run.completed + run.failed) + " of " +
                   std::to_string(todo.size()) + ")");
  };
  mpi::task_farm(
      static_cast<int>(todo.size()), o.jobs,
      [&](int i) { return evaluate_point(cs, o, pl, todo[static_cast<size_t>(i)]).dump(); },
      [&](int i, const std::string& bytes) {
        record(todo[static_cast<size_t>(i)], nlohmann::json::parse(bytes));
      },
      [&](int i, const std::string& why) {
        record(todo[static_cast<size_t>(i)],
               {{"status", "failed"}, {"message", why}, {"wall", NAN}, {"values", {}}});
      });
  run.interrupted = interrupted() != 0;
  if (mpi::world().size > 1)  // every rank ends with rank 0's outcome
    run.ranks_exit = std::stoi(mpi::broadcast(std::to_string(run.exit_code())));
  if (mpi::world().rank != 0) return run;
  nlohmann::json S = sweep_summary(cs, o, pl, run);
  if (writes) {  // sorted by point once every point has run
    appended.close();
    std::string text = header;
    for (const auto& [k, l] : lines) text += l;
    write_file_atomic(o.out_dir + "/sweep.csv", text);
    S["files"] = file_list({"sweep.csv", "sweep.json", "summary.json"});
    write_json_atomic(o.out_dir + "/summary.json", S);
  }
  run.summary = S;
  return run;
}

}  // namespace lsmbs
