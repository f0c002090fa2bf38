#include "lsmbs/runs/geometry.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/geometry/solid_resolution.hpp"
#include "lsmbs/io/design_picture.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/runs/judge.hpp"
#include "lsmbs/runs/shape.hpp"

namespace lsmbs {

std::string GeometryRunOptions::validate() const {
  if (image_width < DesignPictureLayout::kMinWidth || image_width > 20000)
    return "image_width: expected " + std::to_string(DesignPictureLayout::kMinWidth) +
           "..20000 pixels";
  return {};
}

namespace {

// The judgement's resolution options: the case's optimization.judge.min_elements, as after an
// optimization (the default 2 without an optimization section).
ResolutionOptions resolution_options(const Case& cs) {
  ResolutionOptions ro;
  if (cs.raw.contains("optimization") && cs.raw["optimization"].contains("judge"))
    ro.min_elements = parse_optimization(cs).judge.min_elements;
  return ro;
}

// One designed body at p: its mass and gradient, areas and the mapping's counts; with an output
// folder its μ_e and φ as VTU and the picture (their names added to `files`).
nlohmann::json body_json(const Case& cs, const Vec& p, const ModelParams& params,
                         const BodyDesign& bd, const SpMat& dmu, const MapCounts& counts,
                         const GeometryRunOptions& o, std::vector<std::string>& files) {
  const Design& d = *cs.design;
  Vec grad;
  const double mass = Design::mass_gradient(bd, dmu, params, grad);
  const Vec& mu = params.fields[bd.body->field];
  const auto& A = bd.map->element_areas();
  const double mu_min = bd.map->options().mu_min;
  double solid = 0, voids = 0;
  for (int e = 0; e < mu.size(); ++e) {
    solid += A[e];
    voids += A[e] * (1 - mu[e]) / (1 - mu_min);
  }
  nlohmann::json g = nlohmann::json::object();
  for (int k = 0; k < d.size(); ++k) g[d.variables[k].name] = grad[k];
  nlohmann::json jb = {{"body", bd.body->name},
                       {"mass", mass},
                       {"mass_gradient", g},
                       {"domain_area", solid},
                       {"void_area", voids},
                       {"cut_elements", counts.cut},
                       {"band_elements", counts.band},
                       {"elements", mu.size()},
                       {"epsilon", bd.map->epsilon()},
                       {"mu_min", mu_min},
                       {"subgrid", bd.map->options().subgrid},
                       {"band", bd.map->options().band}};
  // what the mesh resolves of the design (runs/judge.hpp)
  jb["resolution"] = resolution_json(judge_resolution(
      bd.body->mesh, bd.map->level_set(), bd.map->level_set().values(p), resolution_options(cs)));
  if (o.out_dir.empty()) return jb;
  const std::string stem = body_file_stems(*cs.model).at(bd.body->name);
  const std::string base = o.out_dir + "/" + stem;
  const Mesh2D& mesh = bd.body->mesh;
  const auto values = bd.map->level_set().values(p);
  Vec phi(mesh.num_nodes());
  for (int i = 0; i < mesh.num_nodes(); ++i)
    phi[i] = bd.map->level_set().evaluate(mesh.nodes[static_cast<size_t>(i)], values, nullptr);
  write_design_vtu(base + ".vtu", mesh, mu, phi);
  write_design_png(base + ".png", mesh, mu, mu_min, phi, o.image_width);
  // the shape as data for CAD and meshing (python/lsmbs/export.py)
  write_json_atomic(base + "_shape.json", shape_json(bd, p, params));
  jb["files"] = {{"vtu", stem + ".vtu"}, {"png", stem + ".png"}, {"shape", stem + "_shape.json"}};
  files.push_back(stem + ".vtu");
  files.push_back(stem + ".png");
  files.push_back(stem + "_shape.json");
  return jb;
}

// One designed solid body at p: its mass and gradient, volumes and the mapping's counts; with an
// output folder its μ_e and φ on the undeformed mesh as VTU.
nlohmann::json solid_body_json(const Case& cs, const Vec& p, const ModelParams& params,
                               const SolidBodyDesign& bd, const SpMat& dmu,
                               const GeometryRunOptions& o, std::vector<std::string>& files) {
  const Design& d = *cs.design;
  const SolidDesignMap& map = *bd.map;
  const Vec& mu = params.fields[bd.body->field];
  MapCounts counts;
  Vec mu_again;
  map.map(p, mu_again, nullptr, &counts);
  Vec grad;
  const double volume = map.material_volume(mu, &dmu, &grad);
  // m = ρ Σ_e μ_e V_e: ∂m/∂p = ρ Σ_e V_e ∂μ_e/∂p = ρ (1 − μ_min) ∂V/∂p
  const double rho = params.scalars[bd.body->rho_param], mu_min = map.options().mu_min;
  double domain = 0;
  for (double v : map.element_volumes()) domain += v;
  nlohmann::json g = nlohmann::json::object(), gv = nlohmann::json::object();
  for (int k = 0; k < d.size(); ++k) {
    g[d.variables[k].name] = rho * (1 - mu_min) * grad[k];
    gv[d.variables[k].name] = grad[k];
  }
  nlohmann::json jb = {{"body", bd.body->name},
                       {"kind", "solid"},
                       {"mass", bd.body->mass(params)},
                       {"mass_gradient", g},
                       {"domain_volume", domain},
                       {"material_volume", volume},
                       {"material_volume_gradient", gv},
                       {"cut_elements", counts.cut},
                       {"band_elements", counts.band},
                       {"elements", mu.size()},
                       {"epsilon", map.epsilon()},
                       {"mu_min", mu_min},
                       {"subgrid", map.options().subgrid},
                       {"band", map.options().band}};
  jb["resolution"] = resolution_json(judge_solid_resolution(
      bd.body->mesh, map.level_set(), bd.num_design_features, p, resolution_options(cs)));
  if (o.out_dir.empty()) return jb;
  const std::string stem = body_file_stems(*cs.model).at(bd.body->name);
  const SolidMesh& mesh = bd.body->mesh;
  const auto values = map.level_set().values(p);
  Vec phi(mesh.num_nodes());  // on the mesh as built: the body at rest at t = 0
  for (int i = 0; i < mesh.num_nodes(); ++i)
    phi[i] = map.level_set().evaluate(mesh.nodes[static_cast<size_t>(i)], values, nullptr);
  write_solid_vtu(o.out_dir + "/" + stem + ".vtu", *bd.body, cs.model->initial_positions(), params,
                  &phi);
  // the shape as data for CAD (python/lsmbs/export.py: STEP)
  write_json_atomic(o.out_dir + "/" + stem + "_shape.json", solid_shape_json(bd, p, params));
  jb["files"] = {{"vtu", stem + ".vtu"}, {"shape", stem + "_shape.json"}};
  files.push_back(stem + ".vtu");
  files.push_back(stem + "_shape.json");
  return jb;
}

}  // namespace

namespace {

// The length-scale constraints of the case's optimization section at p (null without them), and
// a warning for each one the design violates.
nlohmann::json length_scale_report(const Case& cs, const Vec& p, nlohmann::json& warnings) {
  const auto& raw = cs.raw;
  if (!raw.contains("optimization") || !raw["optimization"].contains("length_scale"))
    return nullptr;
  const DesignProblem prob(conditions_of(cs), parse_optimization(cs));
  nlohmann::json J = prob.length_scale_json(p);
  if (J.is_null()) return J;
  for (const auto& [body, b] : J.items())
    for (const auto& c : b["constraints"])
      if (!c["satisfied"].get<bool>()) {
        char w[200];
        std::snprintf(w, sizeof w, "body '%s': length scale %s is %.4g mm, below its %.4g mm",
                      body.c_str(), c["name"].get<std::string>().c_str(),
                      c["value"].get<double>() * 1e3, c["bound"].get<double>() * 1e3);
        warnings.push_back(w);
      }
  return J;
}

}  // namespace

nlohmann::json run_geometry(const Case& cs, const Vec& p, const GeometryRunOptions& o) {
  if (auto msg = o.validate(); !msg.empty()) throw Error("geometry option " + msg);
  if (!cs.design)
    throw Error(cs.file, "/design", "the case has no design section (nothing to map)");
  const auto t0 = std::chrono::steady_clock::now();
  const Design& d = *cs.design;
  ModelParams params = cs.model->params();  // the design is a value: the case is not changed
  const auto degenerate = [&](const auto& features) {
    for (const auto& f : features)
      if (auto msg = f.check(f.values(p)); !msg.empty())
        throw Error(cs.file, "/design",
                    "feature '" + f.name() + "' is degenerate at this design: " + msg);
  };
  for (const auto& b : d.bodies) degenerate(b.map->level_set().features());
  for (const auto& b : d.solid_bodies) degenerate(b.map->level_set().features());
  std::vector<SpMat> dmu;
  d.apply(p, params, &dmu);
  std::vector<MapCounts> counts(d.bodies.size());  // the mapping's diagnostics at p, per body
  for (size_t b = 0; b < d.bodies.size(); ++b) {
    Vec mu;
    d.bodies[b].map->map(p, mu, nullptr, &counts[b]);
  }
  // the length-scale section is checked before anything is written (a bad bound is an input
  // error that leaves no files)
  nlohmann::json length_warnings = nlohmann::json::array();
  const nlohmann::json length_scale = length_scale_report(cs, p, length_warnings);
  if (!o.out_dir.empty()) std::filesystem::create_directories(o.out_dir);
  nlohmann::json bodies = nlohmann::json::array();
  std::vector<std::string> files = {"summary.json"};
  for (size_t b = 0; b < d.bodies.size(); ++b)
    bodies.push_back(body_json(cs, p, params, d.bodies[b], dmu[b], counts[b], o, files));
  for (size_t b = 0; b < d.solid_bodies.size(); ++b)
    bodies.push_back(
        solid_body_json(cs, p, params, d.solid_bodies[b], dmu[d.bodies.size() + b], o, files));
  nlohmann::json S = case_provenance(o.command_line.empty() ? "geometry" : o.command_line, cs);
  S["overrides"] = cs.overrides;
  S["case_name"] = cs.name;
  S["status"] = "complete";
  S["design"] = design_json(cs, p);
  S["bodies"] = bodies;
  S["warnings"] = nlohmann::json::array();
  if (auto w = d.features_outside(p); !w.empty()) S["warnings"].push_back(w);
  for (const auto& b : bodies) {
    const std::string who =
        bodies.size() > 1 ? "body '" + b["body"].get<std::string>() + "': " : std::string();
    const auto& r = b["resolution"];
    if (const auto f = r["pieces_flag"].get<std::string>(); !f.empty())
      S["warnings"].push_back(who + f);
    for (const auto& f : r["flags"]) S["warnings"].push_back(who + f.get<std::string>());
  }
  S["length_scale"] = length_scale;
  for (const auto& w : length_warnings) S["warnings"].push_back(w);
  S["responses"] = nlohmann::json::object();
  for (const auto& b : bodies) S["responses"]["mass." + b["body"].get<std::string>()] = b["mass"];
  S["units"] = {{"responses", nlohmann::json::object()}};
  for (const auto& b : bodies)
    S["units"]["responses"]["mass." + b["body"].get<std::string>()] = "kg";
  S["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.out_dir.empty()) {
    S["files"] = file_list(std::move(files));
    write_json_atomic(o.out_dir + "/summary.json", S);
  }
  return S;
}

}  // namespace lsmbs
