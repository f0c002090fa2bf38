#include "lsmbs/optimization/problem.hpp"

#include <nlopt.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "lsmbs/core/error.hpp"
#include "lsmbs/fem/solid_cell.hpp"
#include "lsmbs/geometry/sampling.hpp"
#include "lsmbs/geometry/solid_length_scale.hpp"
#include "lsmbs/records/json.hpp"

namespace lsmbs {

nlohmann::json OptimizationSpec::to_json() const {
  nlohmann::json c = nlohmann::json::array();
  for (const auto& k : constraints) {  // a plain upper bound keeps the form of earlier checkpoints
    nlohmann::json e = {{"response", k.response}};
    if (k.lower)
      e["lower"] = -k.upper;
    else
      e["upper"] = k.upper;
    if (k.scale > 0) e["scale"] = k.scale;
    c.push_back(e);
  }
  return {{"objective", objective},
          {"constraints", c},
          {"optimizer", optimizer},
          {"sensitivity", nlohmann::json(sensitivity)},
          {"tol_objective", tol_objective},
          {"tol_constraint", tol_constraint},
          {"max_evaluations", max_evaluations},
          {"inner_max_evaluations", inner_max_evaluations},
          {"kkt_tolerance", kkt_tolerance},
          {"move_limit", move_limit},
          {"asymptote_init", asymptote_init},
          {"judge",
           {{"enabled", judge.enabled},
            {"min_elements", judge.min_elements},
            {"ersatz", judge.ersatz},
            {"ersatz_factor", judge.ersatz_factor},
            {"ersatz_tolerance", judge.ersatz_tolerance}}},
          {"length_scale", length_scale.enabled
                               ? nlohmann::json{{"min_size", length_scale.min_size},
                                                {"min_ligament", length_scale.min_ligament},
                                                {"min_edge", length_scale.min_edge},
                                                {"min_member", length_scale.min_member},
                                                {"no_cut", length_scale.no_cut},
                                                {"tolerance", length_scale.tolerance}}
                               : nlohmann::json(nullptr)}};
}

DesignProblem::DesignProblem(const Study& cs, OptimizationSpec spec)
    : DesignProblem(Conditions::single(cs), std::move(spec)) {}

namespace {

// The study and response index of a gathered response name; null study for a combination.
struct ResponseSource {
  const Study* study = nullptr;
  int response = -1;
  const ResponseCombination* combination = nullptr;
};
ResponseSource source_of(const Conditions& c, const std::string& name) {
  for (size_t k = 0; k < c.size(); ++k)
    for (size_t r = 0; r < c.studies[k]->responses.size(); ++r)
      if (c.reported(k, r) && c.response_name(k, r) == name)
        return {c.studies[k], static_cast<int>(r), nullptr};
  for (const auto& comb : c.combinations)
    if (comb.name == name) return {nullptr, -1, &comb};
  return {};
}

// The steps of a per-step response's window on its study's time grid.
int window_steps(const Study& s, const ResponseSpec& r) {
  const double h = s.simulation.h;
  const long n = std::lround(std::ceil(s.simulation.t_end / h - 1e-9));
  int count = 0;
  for (long i = 0; i <= n; ++i) {
    const double t = i * h;
    if (t >= r.t0 - 1e-9 * h && t <= r.t1 + 1e-9 * h) ++count;
  }
  return count;
}

}  // namespace

DesignProblem::DesignProblem(Conditions conditions, OptimizationSpec spec, ConditionExecutor run)
    : conditions_(std::move(conditions)), run_(std::move(run)), spec_(std::move(spec)) {
  if (!run_) run_ = thread_executor(static_cast<int>(std::thread::hardware_concurrency()));
  names_ = conditions_.response_names();
  auto find = [&](const std::string& n) {
    const auto it = std::find(names_.begin(), names_.end(), n);
    return it == names_.end() ? -1 : static_cast<int>(it - names_.begin());
  };
  objective_index_ = find(spec_.objective);
  if (objective_index_ < 0)
    throw SetupError("optimization.objective", "unknown response '" + spec_.objective + "'");
  const ResponseSource obj = source_of(conditions_, spec_.objective);
  if (obj.study && obj.study->responses[obj.response].kind == ResponseSpec::Kind::kPerStep)
    throw SetupError("optimization.objective",
                     "the objective must be a scalar response (not per_step)");
  if (obj.combination && obj.combination->kind == ResponseCombination::Kind::kMax)
    throw SetupError("optimization.objective",
                     "'" + spec_.objective +
                         "' is an exact max: it has a kink where two of its terms tie, which "
                         "the optimizer does not see; minimize a \"ks\" combination (smooth, "
                         "above the max by at most ln(n)/ρ), or a sum");
  // a constraint on an exact max is one constraint per term (the same bound)
  std::vector<OptimizationSpec::Constraint> expanded;
  for (const auto& c : spec_.constraints) {
    const ResponseSource src = source_of(conditions_, c.response);
    if (src.combination && src.combination->kind == ResponseCombination::Kind::kMax) {
      for (const auto& t : src.combination->of) {
        OptimizationSpec::Constraint e = c;
        e.response = t;
        expanded.push_back(e);
      }
      continue;
    }
    expanded.push_back(c);
  }
  for (const auto& c : expanded) {
    const int k = find(c.response);
    if (k < 0)
      throw SetupError("optimization.constraints", "unknown response '" + c.response + "'");
    constraint_index_.push_back(k);
  }
  // the discrete adjoint takes scalar responses; those the optimization does not use are skipped
  if (spec_.sensitivity.is_adjoint()) {
    for (size_t j = 0; j < expanded.size(); ++j) {
      const ResponseSource src = source_of(conditions_, expanded[j].response);
      if (src.study && src.study->responses[src.response].kind == ResponseSpec::Kind::kPerStep)
        throw SetupError("optimization.constraints",
                         "constraint on '" + expanded[j].response +
                             "' is per_step (one constraint per grid step): the adjoint method "
                             "takes scalar responses; constrain an aggregate (max, ks) or use "
                             "sensitivity method direct-analytic");
    }
    spec_.sensitivity.adjoint_skip_per_step = true;
  }
  // per-step constraints: count the steps of the window on the time grid
  for (size_t j = 0; j < expanded.size(); ++j) {
    const auto& c = expanded[j];
    const ResponseSource src = source_of(conditions_, c.response);
    const bool per_step =
        src.study && src.study->responses[src.response].kind == ResponseSpec::Kind::kPerStep;
    const int count = per_step ? window_steps(*src.study, src.study->responses[src.response]) : 1;
    num_constraints_ += count;
    for (int k = 0; k < count; ++k)
      constraint_names_.push_back((c.lower ? "-" : "") + c.response +
                                  (per_step ? "." + std::to_string(k) : ""));
    constraint_upper_.insert(constraint_upper_.end(), static_cast<size_t>(count), c.upper);
    constraint_scale_.insert(constraint_scale_.end(), static_cast<size_t>(count), c.normalizer());
  }
  expanded_ = std::move(expanded);
  num_response_constraints_ = num_constraints_;
  if (spec_.length_scale.enabled) add_length_scales();
}

namespace {

// The member size of a super-ellipse is 2 min(a, b) only for exponents ≥ 2 (convex, its nearest
// boundary point from the centre on an axis); its exponents xi, eta (parameters 4 and 5) are
// affine in the variables: checked at the bounds.
void check_member_exponents(const std::string& feature, const std::vector<ParamBinding>& params,
                            const Design& d) {
  for (int k : {4, 5}) {
    const ParamBinding& pb = params[static_cast<size_t>(k)];
    const double lo =
        pb.variable < 0 ? pb.offset : std::min(pb.value(d.lower()), pb.value(d.upper()));
    if (lo < 2)
      throw SetupError("optimization.length_scale.min_member",
                       "feature '" + feature + "' has an exponent below 2 (" + std::to_string(lo) +
                           ") within the design bounds, where its width is not 2 min(a, b); "
                           "set min_member to 0 or keep xi, eta >= 2");
  }
}

// A bound longer than the body itself is no length scale of it (a length in mm given as m?).
void check_bounds_fit(const LengthScaleOptions& o, const std::string& body, double size) {
  for (const auto& [key, v] : {std::pair{"min_ligament", o.min_ligament},
                               {"min_edge", o.min_edge},
                               {"min_member", o.min_member},
                               {"no_cut", o.no_cut}})
    if (v > size)
      throw SetupError("optimization.length_scale." + std::string(key),
                       std::to_string(v) + " m exceeds the size of body '" + body + "' (" +
                           std::to_string(size) +
                           " m, its bounding box's largest extent): lengths are in metres "
                           "(min_size sets the three bounds together)");
}

}  // namespace

LengthScaleOptions DesignProblem::length_scale_options(double element_size) const {
  const auto& L = spec_.length_scale;
  const double size = L.min_size >= 0 ? L.min_size : spec_.judge.min_elements * element_size;
  auto pick = [&](double v) { return v >= 0 ? v : size; };
  LengthScaleOptions o;
  o.min_ligament = pick(L.min_ligament), o.min_edge = pick(L.min_edge);
  o.min_member = pick(L.min_member), o.no_cut = L.no_cut;
  o.tolerance = L.tolerance;
  if (auto msg = o.validate(); !msg.empty()) throw SetupError("optimization.length_scale", msg);
  return o;
}

void DesignProblem::add_length_scales() {
  const Design& d = design();
  if (d.bodies.empty() && d.solid_bodies.empty())
    throw SetupError("optimization.length_scale",
                     "the design has no level-set geometry to constrain (design.geometry)");
  for (const BodyDesign& b : d.bodies) {
    const LengthScaleOptions o = length_scale_options(median_element_size(b.body->mesh));
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (const Vec2& x : b.body->mesh.nodes)
      for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], x[k]), hi[k] = std::max(hi[k], x[k]);
    check_bounds_fit(o, b.body->name, std::max(hi[0] - lo[0], hi[1] - lo[1]));
    const LevelSet& ls = b.map->level_set();
    for (int i = 0; i < b.num_design_features && o.min_member > 0; ++i)
      if (ls.features()[static_cast<size_t>(i)].type() == Feature::Type::kBSpline)
        throw SetupError("optimization.length_scale.min_member",
                         "feature '" + ls.features()[static_cast<size_t>(i)].name() +
                             "' is a B-spline: a free-form feature has no member size; set "
                             "min_member to 0 (its ligaments, edge and no_cut are constrained; "
                             "docs/designs.md)");
    for (int i = 0; i < b.num_design_features && o.min_member > 0; ++i) {
      const Feature& f = ls.features()[static_cast<size_t>(i)];
      if (f.type() == Feature::Type::kSuperEllipse) check_member_exponents(f.name(), f.params(), d);
    }
    add_length_scale(b.body->name, std::make_unique<lsmbs::LengthScale>(b.body->mesh, ls,
                                                                        b.num_design_features, o));
  }
  for (const SolidBodyDesign& b : d.solid_bodies) {
    const LengthScaleOptions o = length_scale_options(median_longest_edge(b.body->mesh));
    check_bounds_fit(o, b.body->name, b.body->mesh.size());
    if (o.no_cut > 0)
      throw SetupError("optimization.length_scale.no_cut",
                       "no_cut is planar only, and '" + b.body->name +
                           "' is a solid body: bound the distance from its features to its faces "
                           "with min_edge (docs/designs.md, \"Length-scale control\")");
    const LevelSet3& ls = b.map->level_set();
    for (int i = 0; i < b.num_design_features && o.min_member > 0; ++i) {
      const Feature3& f = ls.features()[static_cast<size_t>(i)];
      if ((f.type() == Feature3::Type::kPocket || f.type() == Feature3::Type::kThroughHole) &&
          f.profile() == Feature::Type::kSuperEllipse)
        check_member_exponents(f.name(), f.params(), d);
    }
    add_length_scale(b.body->name, std::make_unique<SolidLengthScale>(b.body->mesh, ls,
                                                                      b.num_design_features, o));
  }
}

void DesignProblem::add_length_scale(const std::string& body,
                                     std::unique_ptr<LengthScaleMeasures> measures) {
  BodyLengthScale bl;
  bl.body = body;
  bl.measures = std::move(measures);
  bl.measures->leave_out_overlaps(design().initial());  // one void by design: no ligament
  const auto names = bl.measures->names();
  const auto values = bl.measures->evaluate(design().initial());  // the bounds, in names' order
  for (size_t k = 0; k < names.size(); ++k) {
    constraint_names_.push_back("-length_scale." + bl.body + "." + names[k]);
    constraint_upper_.push_back(-values[k].bound);
    constraint_scale_.push_back(values[k].bound);
  }
  num_constraints_ += static_cast<int>(names.size());
  length_scales_.push_back(std::move(bl));
}

double DesignProblem::geometric_violation(const Vec& p, Vec* g, Mat* J) const {
  std::vector<double> v, b;
  std::vector<Vec> grads;
  for (const auto& bl : length_scales_)
    for (const auto& c : bl.measures->evaluate(p)) {
      v.push_back(c.value), b.push_back(c.bound), grads.push_back(c.gradient);
    }
  double worst = v.empty() ? 0.0 : -INFINITY;
  if (g) g->resize(static_cast<Eigen::Index>(v.size()));
  if (J) J->resize(static_cast<Eigen::Index>(v.size()), p.size());
  for (size_t k = 0; k < v.size(); ++k) {  // (δ − value)/δ ≤ 0
    const double s = (b[k] - v[k]) / b[k];
    worst = std::max(worst, s);
    if (g) (*g)[static_cast<Eigen::Index>(k)] = s;
    if (J) J->row(static_cast<Eigen::Index>(k)) = -grads[k].transpose() / b[k];
  }
  return worst;
}

Vec DesignProblem::admissible_start(const Vec& p0, double* violation) const {
  if (length_scales_.empty()) {
    if (violation) *violation = 0;
    return p0;
  }
  const Design& d = design();
  const Vec lo = d.lower(), hi = d.upper(), range = hi - lo;
  const int n = static_cast<int>(p0.size());
  int m = 0;
  for (const auto& bl : length_scales_) m += static_cast<int>(bl.measures->names().size());
  struct Data {
    const DesignProblem* self;
    Vec p0, range;
  } data{this, p0, range};
  auto objective = [](unsigned nn, const double* x, double* grad, void* f) -> double {
    const auto& D = *static_cast<Data*>(f);
    double s = 0;
    for (unsigned i = 0; i < nn; ++i) {
      const double r = (x[i] - D.p0[i]) / D.range[i];
      s += r * r;
      if (grad) grad[i] = 2 * r / D.range[i];
    }
    return s;
  };
  auto constraints = [](unsigned mm, double* result, unsigned nn, const double* x, double* grad,
                        void* f) {
    const auto& D = *static_cast<Data*>(f);
    const Vec p = Eigen::Map<const Vec>(x, nn);
    Vec g;
    Mat J;
    D.self->geometric_violation(p, &g, grad ? &J : nullptr);
    for (unsigned k = 0; k < mm; ++k) {
      result[k] = g[k];
      if (grad)
        for (unsigned i = 0; i < nn; ++i) grad[k * nn + i] = J(k, i);
    }
  };
  nlopt_opt opt = nlopt_create(NLOPT_LD_SLSQP, static_cast<unsigned>(n));
  nlopt_set_lower_bounds(opt, lo.data());
  nlopt_set_upper_bounds(opt, hi.data());
  nlopt_set_min_objective(opt, objective, &data);
  const std::vector<double> tol(static_cast<size_t>(m), 1e-6);
  nlopt_add_inequality_mconstraint(opt, static_cast<unsigned>(m), constraints, &data, tol.data());
  nlopt_set_xtol_rel(opt, 1e-8);
  nlopt_set_maxeval(opt, 300);
  std::vector<double> x(p0.data(), p0.data() + n);
  double f = 0;
  nlopt_optimize(opt, x.data(), &f);
  nlopt_destroy(opt);
  Vec p = Eigen::Map<const Vec>(x.data(), n);
  for (int i = 0; i < n; ++i) p[i] = std::clamp(p[i], lo[i], hi[i]);
  const double v = geometric_violation(p, nullptr, nullptr);
  const double v0 = geometric_violation(p0, nullptr, nullptr);
  if (violation) *violation = std::min(v, v0);
  return v <= v0 ? p : p0;
}

double DesignProblem::response_violation(const Evaluation& e) const {
  if (!e.ok) return NAN;
  double v = num_response_constraints_ == 0 ? 0.0 : -INFINITY;
  for (int j = 0; j < num_response_constraints_; ++j) {
    const size_t k = static_cast<size_t>(j);
    v = std::max(v, (e.constraints[k] - e.upper[k]) / e.scale[k]);
  }
  return v;
}

nlohmann::json DesignProblem::length_scale_json(const Vec& p) const {
  if (length_scales_.empty()) return nullptr;
  nlohmann::json J = nlohmann::json::object();
  for (const auto& bl : length_scales_) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& c : bl.measures->evaluate(p))
      a.push_back({{"name", c.name()},
                   {"kind", c.kind},
                   {"features",
                    c.second.empty() ? nlohmann::json{c.first} : nlohmann::json{c.first, c.second}},
                   {"value", c.value},
                   {"bound", c.bound},
                   {"satisfied", c.value >= c.bound},
                   {"error_bound", c.error_bound},
                   {"at", std::vector<double>(c.at.data(), c.at.data() + c.at.size())}});
    J[bl.body] = {{"spacing", bl.measures->spacing()},
                  {"constraints", a},
                  {"left_out", bl.measures->left_out()}};
  }
  return J;
}

void DesignProblem::evaluate_length_scales(Evaluation& e, int& row) const {
  // state-independent: the same exact gradient whatever the sensitivity method; as a lower bound
  // value ≥ δ in the optimizer's form −value ≤ −δ
  for (const auto& bl : length_scales_)
    for (const auto& c : bl.measures->evaluate(e.p)) {
      e.constraints.push_back(-c.value);
      e.upper.push_back(-c.bound);
      e.scale.push_back(c.bound);
      e.constraint_gradient.row(row) = -c.gradient.transpose();
      e.max_violation = std::max(e.max_violation, (-c.value + c.bound) / c.bound);
      ++row;
    }
}

void DesignProblem::seed(const Evaluation& e) {
  cache_[std::vector<double>(e.p.data(), e.p.data() + e.p.size())] = e;
}

const Evaluation& DesignProblem::evaluate(const Vec& p) {
  std::vector<double> key(p.data(), p.data() + p.size());
  if (auto it = cache_.find(key); it != cache_.end()) {
    ++cache_hits_;
    return it->second;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const auto res = merge(conditions_, compute_conditions(conditions_, p, spec_.sensitivity, run_));
  ++simulations_;
  Evaluation e;
  e.p = p;
  e.ok = res.ok;
  e.message = res.message;
  // the gathered responses by their index in names_ (a failed condition leaves some out)
  std::vector<const ResponseSensitivity*> by_index(names_.size(), nullptr);
  for (const auto& r : res.responses) {
    const auto it = std::find(names_.begin(), names_.end(), r.name);
    if (it != names_.end()) by_index[static_cast<size_t>(it - names_.begin())] = &r;
  }
  static const ResponseSensitivity kNone;
  auto response = [&](int i) -> const ResponseSensitivity& {
    const auto* r = by_index[static_cast<size_t>(i)];
    if (!r && e.ok) {
      e.ok = false;
      e.message = "response '" + names_[static_cast<size_t>(i)] + "' was not computed";
    }
    return r ? *r : kNone;
  };
  const auto& obj = response(objective_index_);
  auto note_extreme = [&](const ResponseSensitivity& r) {
    if (std::isfinite(r.extreme_time)) e.extreme_times[r.name] = r.extreme_time;
  };
  note_extreme(obj);
  for (int j : constraint_index_) note_extreme(response(j));
  e.objective = obj.values.empty() ? NAN : obj.values[0];
  e.objective_gradient =
      obj.gradient.rows() ? Vec(obj.gradient.row(0).transpose()) : Vec::Zero(p.size());
  e.constraint_gradient.resize(num_constraints_, p.size());
  int row = 0;
  // the maximum over the constraints; a problem without any has nothing to violate: 0 (not the
  // empty maximum −∞, which JSON cannot hold: summary.json wrote null, read back as not feasible)
  e.max_violation = num_constraints_ == 0 ? 0.0 : -INFINITY;
  for (size_t j = 0; j < constraint_index_.size(); ++j) {
    const auto& r = response(constraint_index_[j]);
    const auto& spec = expanded_[j];
    const double ub = spec.upper, sign = spec.lower ? -1.0 : 1.0, sc = spec.normalizer();
    for (size_t k = 0; k < r.values.size() && row < num_response_constraints_; ++k, ++row) {
      const double g = sign * r.values[k];
      e.constraints.push_back(g);
      e.upper.push_back(ub);
      e.scale.push_back(sc);
      e.constraint_gradient.row(row) = sign * r.gradient.row(static_cast<Eigen::Index>(k));
      e.max_violation = std::max(e.max_violation, (g - ub) / sc);
    }
  }
  if (row != num_response_constraints_ && e.ok) {  // a failed run's own message says when and why
    e.ok = false;
    e.message = "a per-step constraint produced " + std::to_string(row) + " values instead of " +
                std::to_string(num_response_constraints_) + " (the run did not reach t_end?)";
  }
  if (e.ok) evaluate_length_scales(e, row);
  if (!e.ok) {  // the aggregates of a run that stopped early are not the responses of this design:
                // NaN everywhere, in the shapes of a complete evaluation (m constraints)
    e.objective = NAN;
    e.max_violation = NAN;
    e.objective_gradient.setConstant(p.size(), NAN);
    e.constraints.assign(static_cast<size_t>(num_constraints_), NAN);
    e.upper = constraint_upper_;
    e.scale = constraint_scale_;
    e.constraint_gradient.setConstant(num_constraints_, p.size(), NAN);
    e.extreme_times.clear();
  }
  e.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (res.interrupted) {  // not a result of p: evaluated again when the run resumes
    e.interrupted = true;
    return interrupted_ = e;
  }
  return cache_[key] = e;
}

namespace {
std::string hex(double v) {
  uint64_t b;
  std::memcpy(&b, &v, 8);
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(b));
  return s;
}
double unhex(const std::string& s) {
  // exactly the 16 hexadecimal digits hex() writes: a prefix parser read "3ff0zz" as 0x3ff0
  uint64_t b = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), b, 16);
  if (s.size() != 16 || ec != std::errc() || end != s.data() + s.size())
    throw std::invalid_argument("'" + s.substr(0, 40) + "' is not 16 hexadecimal digits");
  double v;
  std::memcpy(&v, &b, 8);
  return v;
}
nlohmann::json hexv(const double* d, size_t n) {
  nlohmann::json a = nlohmann::json::array();
  for (size_t i = 0; i < n; ++i) a.push_back(hex(d[i]));
  return a;
}
std::vector<double> unhexv(const nlohmann::json& a) {
  std::vector<double> v;
  for (const auto& x : a) v.push_back(unhex(x.get<std::string>()));
  return v;
}
}  // namespace

nlohmann::json evaluation_to_json(const Evaluation& e) {
  return {{"p", hexv(e.p.data(), e.p.size())},
          {"objective", hex(e.objective)},
          {"constraints", hexv(e.constraints.data(), e.constraints.size())},
          {"upper", hexv(e.upper.data(), e.upper.size())},
          {"scale", hexv(e.scale.data(), e.scale.size())},
          {"objective_gradient", hexv(e.objective_gradient.data(), e.objective_gradient.size())},
          {"constraint_gradient", hexv(e.constraint_gradient.data(), e.constraint_gradient.size())},
          {"rows", e.constraint_gradient.rows()},
          {"max_violation", hex(e.max_violation)},
          {"wall_seconds", e.wall_seconds},
          {"ok", e.ok},
          {"message", e.message},
          {"extreme_times", [&] {
             nlohmann::json t = nlohmann::json::object();
             for (const auto& [name, time] : e.extreme_times) t[name] = hex(time);
             return t;
           }()}};
}

Evaluation evaluation_from_json(const nlohmann::json& j) {
  Evaluation e;
  const auto p = unhexv(j.at("p"));
  e.p = Eigen::Map<const Vec>(p.data(), static_cast<Eigen::Index>(p.size()));
  e.objective = unhex(j.at("objective"));
  e.constraints = unhexv(j.at("constraints"));
  e.upper = unhexv(j.at("upper"));
  if (j.contains("scale")) {
    e.scale = unhexv(j.at("scale"));
  } else {  // a checkpoint from before lower bounds: every constraint was scaled by |bound|
    for (double u : e.upper) e.scale.push_back(std::abs(u));
  }
  const auto g = unhexv(j.at("objective_gradient"));
  e.objective_gradient = Eigen::Map<const Vec>(g.data(), static_cast<Eigen::Index>(g.size()));
  const auto cg = unhexv(j.at("constraint_gradient"));
  const Eigen::Index rows = j.at("rows").get<Eigen::Index>();
  if (rows < 0 || (rows > 0 && static_cast<Eigen::Index>(cg.size()) % rows != 0))
    throw std::invalid_argument("constraint gradient of " + std::to_string(cg.size()) +
                                " values in " + std::to_string(rows) + " rows");
  e.constraint_gradient = Eigen::Map<const Mat>(
      cg.data(), rows, rows ? static_cast<Eigen::Index>(cg.size()) / rows : 0);
  e.max_violation = unhex(j.at("max_violation"));
  e.wall_seconds = j.at("wall_seconds").get<double>();
  e.ok = j.at("ok").get<bool>();
  e.message = j.at("message").get<std::string>();
  if (j.contains("extreme_times"))  // absent in checkpoints written before it was recorded
    for (const auto& [name, time] : j.at("extreme_times").items())
      e.extreme_times[name] = unhex(time.get<std::string>());
  return e;
}

std::optional<GradientCheckResult> check_problem_gradients(DesignProblem& problem, const Vec& p,
                                                           const GradientCheckOptions& o) {
  const OptimizationSpec& spec = problem.spec();
  const Conditions& c = problem.conditions();
  const auto sres = merge(c, compute_conditions(c, p, spec.sensitivity, problem.executor()));
  if (!sres.ok) return std::nullopt;
  std::vector<ResponseSensitivity> used;
  for (const auto& r : sres.responses) {
    bool use = r.name == spec.objective;
    for (const auto& k : spec.constraints) use |= r.name == k.response;
    if (use) used.push_back(r);
  }
  return check_gradients(c, p, used, o, problem.executor());
}

}  // namespace lsmbs
