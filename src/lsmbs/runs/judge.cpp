#include "lsmbs/runs/judge.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/design/design.hpp"
#include "lsmbs/geometry/solid_resolution.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"
#include "lsmbs/sensitivity/wire.hpp"

namespace lsmbs {
namespace {

// The study's parameters at p with the ersatz material's μ_min scaled by `factor` in every
// designed body (the mapping's eq. 5 rescaled: the same H, a smaller floor).
ModelParams weaker_void(const Study& s, const Vec& p, double factor) {
  ModelParams params = parameters_at(s, p);
  auto rescale = [&](double m, int field) {
    const double w = m * factor;
    Vec& mu = params.fields[static_cast<size_t>(field)];
    for (Eigen::Index e = 0; e < mu.size(); ++e) mu[e] = w + (1 - w) * (mu[e] - m) / (1 - m);
  };
  for (const BodyDesign& b : s.design->bodies) rescale(b.map->options().mu_min, b.body->field);
  for (const SolidBodyDesign& b : s.design->solid_bodies)
    rescale(b.map->options().mu_min, b.body->field);
  return params;
}

// The responses the optimization reads, with the largest bound each is held to (0: none).
std::map<std::string, double> judged_responses(const OptimizationSpec& spec) {
  std::map<std::string, double> r{{spec.objective, 0.0}};
  for (const auto& c : spec.constraints) r[c.response] = std::max(r[c.response], std::abs(c.upper));
  return r;
}

std::string percent(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g %%", 100 * x);
  return b;
}

// Each judged response as mapped (a) and with the weaker void (b), flagged beyond the tolerance.
void compare(const std::vector<ResponseSensitivity>& a, const std::vector<ResponseSensitivity>& b,
             const OptimizationSpec& spec, DesignJudgement& J) {
  const double factor = spec.judge.ersatz_factor;
  for (const auto& [name, bound] : judged_responses(spec)) {
    const auto ia = std::find_if(a.begin(), a.end(), [&](const auto& r) { return r.name == name; });
    const auto ib = std::find_if(b.begin(), b.end(), [&](const auto& r) { return r.name == name; });
    if (ia == a.end() || ib == b.end() || ia->values.empty()) continue;
    DesignJudgement::Response R;
    R.name = name;
    double scale = bound, diff = 0;
    R.value = R.weak = -INFINITY;
    for (size_t s = 0; s < ia->values.size() && s < ib->values.size(); ++s) {
      scale = std::max(scale, std::abs(ia->values[s]));
      diff = std::max(diff, std::abs(ib->values[s] - ia->values[s]));
      R.value = std::max(R.value, ia->values[s]);
      R.weak = std::max(R.weak, ib->values[s]);
    }
    R.change = scale > 0 ? diff / scale : diff;
    R.flagged = !(R.change <= spec.judge.ersatz_tolerance);
    if (R.flagged) {
      char v[96];
      std::snprintf(v, sizeof v, "%.6g to %.6g", R.value, R.weak);
      J.structure_flags.push_back("response '" + name + "' changes by " + percent(R.change) + " (" +
                                  v + ") when the void's ersatz material is 1/" +
                                  std::to_string(long(std::lround(1 / factor))) +
                                  " as stiff: a load path runs through void (tolerance " +
                                  percent(spec.judge.ersatz_tolerance) + ")");
    }
    J.responses.push_back(R);
  }
}

void ersatz_check(const Conditions& c, const OptimizationSpec& spec, const Vec& p,
                  const ConditionExecutor& run, DesignJudgement& J) {
  const double factor = spec.judge.ersatz_factor;
  const int n = static_cast<int>(c.size());
  // tasks 0 … n−1: the conditions as mapped; n … 2n−1: with the weaker void
  std::vector<SensitivityResult> as_mapped(c.size()), weak(c.size());
  std::vector<std::string> failed(2 * c.size());
  ConditionTasks t;
  t.n = 2 * n;
  const auto costs = c.costs();
  t.cost.insert(t.cost.end(), costs.begin(), costs.end());
  t.cost.insert(t.cost.end(), costs.begin(), costs.end());
  t.run = [&](int k) {
    const Study& s = *c.studies[static_cast<size_t>(k % n)];
    SensitivityCounts counts;
    try {
      auto& out = (k < n ? as_mapped : weak)[static_cast<size_t>(k % n)];
      out.responses =
          k < n ? simulate_responses(s, p, counts)
                : simulate_responses_with(s, weaker_void(s, p, factor), counts, nullptr, {}, 1);
    } catch (const Interrupted&) {
      throw;
    } catch (const NumericalFailure& e) {
      failed[static_cast<size_t>(k)] = e.what();
    }
  };
  t.save = [&](int k) {
    const auto& r = (k < n ? as_mapped : weak)[static_cast<size_t>(k % n)].responses;
    return nlohmann::json{{"failed", failed[static_cast<size_t>(k)]}, {"r", to_wire(r)}}.dump();
  };
  t.load = [&](int k, const std::string& b) {
    const auto j = nlohmann::json::parse(b);
    failed[static_cast<size_t>(k)] = j["failed"].get<std::string>();
    (k < n ? as_mapped : weak)[static_cast<size_t>(k % n)].responses =
        responses_from_wire(j["r"].get<std::string>());
  };
  run(t);
  J.ersatz_ran = true;
  J.mu_min_factor = factor;
  for (int k = 0; k < 2 * n; ++k) {
    if (failed[static_cast<size_t>(k)].empty()) continue;
    const std::string& cond = c.names[static_cast<size_t>(k % n)];
    J.ersatz_failure = (cond.empty() ? std::string() : "condition '" + cond + "': ") +
                       failed[static_cast<size_t>(k)];
    J.structure_flags.push_back(k < n
                                    ? "the design could not be simulated again: " + J.ersatz_failure
                                    : "with the void's ersatz material 1/" +
                                          std::to_string(long(std::lround(1 / factor))) +
                                          " as stiff the simulation fails (" + J.ersatz_failure +
                                          "): the design rests on the void");
    return;
  }
  compare(gather(c, as_mapped), gather(c, weak), spec, J);
}

nlohmann::json point(const Vec& x) { return std::vector<double>(x.data(), x.data() + x.size()); }

}  // namespace

nlohmann::json resolution_json(const ResolutionReport& R) {
  nlohmann::json parts = nlohmann::json::array();
  for (const NarrowPart& p : R.parts)
    parts.push_back({{"kind", p.kind == NarrowPart::Kind::kHole ? "hole" : "ligament"},
                     {"between", p.kind == NarrowPart::Kind::kHole
                                     ? nlohmann::json::array({p.first})
                                     : nlohmann::json::array({p.first, p.second})},
                     {"width", p.width},
                     {"threshold", p.threshold},
                     {"at", point(p.at)},
                     {"unresolved", p.unresolved}});
  return {{"element_size", R.element_size},
          {"threshold", R.threshold},
          {"accuracy", R.spacing},
          {"pieces", R.pieces},
          {"parts", parts},
          {"flags", R.flags()},
          {"pieces_flag", R.pieces_flag()}};
}

nlohmann::json DesignJudgement::to_json() const {
  nlohmann::json bj = nlohmann::json::array();
  for (const Body& b : bodies) {
    nlohmann::json r = resolution_json(b.resolution);
    r["body"] = b.name;
    bj.push_back(r);
  }
  nlohmann::json ej = nullptr;
  if (ersatz_ran) {
    nlohmann::json rj = nlohmann::json::array();
    for (const Response& r : responses)
      rj.push_back({{"response", r.name},
                    {"value", r.value},
                    {"weak_void", r.weak},
                    {"change", r.change},
                    {"flagged", r.flagged}});
    ej = {{"mu_min_factor", mu_min_factor}, {"responses", rj}};
    if (!ersatz_failure.empty()) ej["failure"] = ersatz_failure;
  }
  return {{"verdict", verdict_name(verdict())},
          {"sound", sound()},
          {"flags", flags()},
          {"structure_flags", structure_flags},
          {"resolution_flags", resolution_flags},
          {"resolution", bj},
          {"load_path", ej}};
}

DesignJudgement::Verdict DesignJudgement::verdict() const {
  return !structure_flags.empty()    ? Verdict::kNotAStructure
         : !resolution_flags.empty() ? Verdict::kUnresolved
                                     : Verdict::kSound;
}

const char* DesignJudgement::verdict_name(Verdict v) {
  return v == Verdict::kSound        ? "sound"
         : v == Verdict::kUnresolved ? "unresolved"
                                     : "not a structure";
}

std::vector<std::string> DesignJudgement::flags() const {
  std::vector<std::string> f = structure_flags;
  f.insert(f.end(), resolution_flags.begin(), resolution_flags.end());
  return f;
}

DesignJudgement judge_design(const Conditions& c, const OptimizationSpec& spec, const Vec& p,
                             const ConditionExecutor& run) {
  DesignJudgement J;
  const Design& d = *c.first().design;
  ResolutionOptions ro;
  ro.min_elements = spec.judge.min_elements;
  for (const BodyDesign& b : d.bodies) {
    DesignJudgement::Body jb{b.body->name, judge_resolution(b.body->mesh, b.map->level_set(),
                                                            b.map->level_set().values(p), ro)};
    const size_t bodies = d.bodies.size() + d.solid_bodies.size();
    const std::string who = bodies > 1 ? "body '" + b.body->name + "': " : "";
    for (const std::string& f : jb.resolution.flags()) J.resolution_flags.push_back(who + f);
    if (auto f = jb.resolution.pieces_flag(); !f.empty()) J.structure_flags.push_back(who + f);
    J.bodies.push_back(std::move(jb));
  }
  for (const SolidBodyDesign& b : d.solid_bodies) {
    DesignJudgement::Body jb{b.body->name, judge_solid_resolution(b.body->mesh, b.map->level_set(),
                                                                  b.num_design_features, p, ro)};
    const size_t bodies = d.bodies.size() + d.solid_bodies.size();
    const std::string who = bodies > 1 ? "body '" + b.body->name + "': " : "";
    for (const std::string& f : jb.resolution.flags()) J.resolution_flags.push_back(who + f);
    if (auto f = jb.resolution.pieces_flag(); !f.empty()) J.structure_flags.push_back(who + f);
    J.bodies.push_back(std::move(jb));
  }
  if (spec.judge.ersatz && !(d.bodies.empty() && d.solid_bodies.empty()))
    ersatz_check(c, spec, p, run, J);
  return J;
}

}  // namespace lsmbs
