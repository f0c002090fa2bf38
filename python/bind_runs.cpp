#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "lsmbs/geometry/solid_resolution.hpp"
#include "lsmbs/runs/judge.hpp"
#include "lsmbs/runs/shape.hpp"
#include "lsmbs/runs/sweep.hpp"
#include "python/support.hpp"

namespace lsmbs_python {

// lsmbs.simulate and its SimulationResult.
void bind_simulate(py::module_& m) {
  py::class_<SimulationResult>(m, "SimulationResult")
      .def_property_readonly("status",
                             [](const SimulationResult& r) { return run_status_name(r.status()); })
      .def("report", &SimulationResult::report)
      .def_property_readonly("times", [](const SimulationResult& r) { return array(r.times); })
      .def_property_readonly("columns", [](const SimulationResult& r) { return r.columns; })
      .def_property_readonly("history",
                             [](const SimulationResult& r) {
                               Mat h(static_cast<Eigen::Index>(r.history.size()),
                                     static_cast<Eigen::Index>(r.columns.size()));
                               for (size_t i = 0; i < r.history.size(); ++i)
                                 for (size_t j = 0; j < r.columns.size(); ++j)
                                   h(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
                                       r.history[i][j];
                               return array(h);
                             })
      .def("column",
           [](const SimulationResult& r, const std::string& name) { return array(r.column(name)); })
      .def_property_readonly(
          "responses",
          [](const SimulationResult& r) {
            py::dict d;  // NaN when the run did not reach t_end; per-step responses as arrays
            for (const auto& [name, v] : r.responses) {
              const auto ps = r.per_step.find(name);
              d[py::str(name)] = ps != r.per_step.end() ? py::object(array(ps->second))
                                                        : py::object(py::float_(v));
            }
            return d;
          },
          "{response: value}: a float, or an array over the window's steps for a per-step "
          "response; NaN when the run did not reach t_end")
      .def_property_readonly("summary",
                             [](const SimulationResult& r) { return json_to_python(r.summary); })
      .def_property_readonly(
          "conditions",
          [](const SimulationResult& r) {
            py::dict d;  // each condition's run (copies)
            for (const auto& [name, run] : r.conditions) d[py::str(name)] = py::cast(run);
            return d;
          },
          "with service conditions: {condition: its SimulationResult}; else empty");

  m.def(
      "simulate",
      [](const CasePtr& cs, const py::object& design, const std::filesystem::path& out_dir,
         bool overwrite, const py::object& progress) {
        const CaseTurn turn(*cs);
        const Vec p = prepared(*cs, design);  // the design is in the model's parameters now
        return claimed(cs->model.get(), out_dir, overwrite, false, [&](OutputClaim&) {
          RunOptions ro;
          ro.out_dir = out_dir;
          ro.design_point = p;
          PythonRun run(progress);
          ro.progress = run.progress();
          return run([&] { return located(*cs, [&] { return run_simulation(*cs, ro); }); });
        });
      },
      py::arg("case").none(false), py::arg("design") = py::none(), py::arg("out_dir") = "",
      py::arg("overwrite") = false, py::arg("progress") = py::none(),
      "Generalized-α simulation (Algorithm 1); design: None, a sequence, or {name: value}");
}

// lsmbs.static and its StaticResult.
void bind_static(py::module_& m) {
  py::class_<StaticRunResult>(m, "StaticResult")
      .def_property_readonly("status",
                             [](const StaticRunResult& r) { return run_status_name(r.status()); })
      .def("report", &StaticRunResult::report)
      .def_property_readonly("iterations",
                             [](const StaticRunResult& r) { return r.solver.iterations; })
      .def_property_readonly("columns", [](const StaticRunResult& r) { return r.columns; })
      .def_property_readonly("measures",
                             [](const StaticRunResult& r) {
                               py::dict d;
                               for (size_t i = 0; i < r.columns.size(); ++i)
                                 d[py::str(r.columns[i])] = r.measures[i];
                               return d;
                             })
      .def_property_readonly("responses", [](const StaticRunResult& r) { return r.responses; })
      .def_property_readonly("q", [](const StaticRunResult& r) { return array(r.state.q); })
      .def_property_readonly("summary",
                             [](const StaticRunResult& r) { return json_to_python(r.summary); });

  m.def(
      "static",
      [](const CasePtr& cs, const py::object& design, double t, int max_iter,
         const std::filesystem::path& out_dir, bool overwrite) {
        const CaseTurn turn(*cs);
        const Vec p = prepared(*cs, design);  // the design is in the model's parameters now
        return claimed(cs->model.get(), out_dir, overwrite, false, [&](OutputClaim&) {
          StaticRunOptions o;
          o.out_dir = out_dir;
          o.t = t;
          o.max_iter = max_iter;
          o.design_point = p;
          o.command_line = "lsmbs.static (Python)";
          PythonRun run{py::none()};
          return run([&] { return located(*cs, [&] { return run_static(*cs, o); }); });
        });
      },
      py::arg("case").none(false), py::arg("design") = py::none(), py::arg("t") = 0.0,
      py::arg("max_iter") = 50, py::arg("out_dir") = "", py::arg("overwrite") = false,
      "Static equilibrium at time t (drivers and loads at t; no inertia), as `lsmbs static`");
}

// A designed solid body as lsmbs.geometry gives it: its mesh, μ_e, the nodal level set, the mass
// ρ0 Σ_e μ_e V_e and its gradient ρ0 Σ_e V_e ∂μ_e/∂p (dmu: elements × variables), its shape.
static py::dict solid_geometry(const SolidBodyDesign& bd, const Vec& p, const ModelParams& params,
                               const SpMat& dmu) {
  const SolidBody& body = *bd.body;
  const SolidMesh& mesh = body.mesh;
  Mat nodes(mesh.num_nodes(), 3);
  Vec phi(mesh.num_nodes());
  const auto values = bd.map->level_set().values(p);
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    nodes.row(i) = mesh.nodes[static_cast<size_t>(i)].transpose();
    phi[i] = bd.map->level_set().evaluate(mesh.nodes[static_cast<size_t>(i)], values, nullptr);
  }
  py::list cells, types;
  Vec rho_v(mesh.num_elements());
  const double rho0 = params.scalars[static_cast<size_t>(body.rho_param)];
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto& c = mesh.cells[static_cast<size_t>(e)];
    cells.append(py::array_t<int>(static_cast<py::ssize_t>(c.size()), c.data()));
    types.append(c.size() == 8 ? "hex8" : "tet4");
    rho_v[e] = rho0 * body.elements[static_cast<size_t>(e)]->volume();
  }
  const Vec grad = dmu.transpose() * rho_v;
  return py::dict(py::arg("nodes") = array(nodes), py::arg("cells") = cells,
                  py::arg("cell_types") = types, py::arg("quads") = py::none(),
                  py::arg("mu") = array(params.fields[static_cast<size_t>(body.field)]),
                  py::arg("phi") = array(phi), py::arg("mass") = body.mass(params),
                  py::arg("mass_gradient") = array(grad),
                  py::arg("shape") = json_to_python(solid_shape_json(bd, p, params)),
                  py::arg("resolution") = json_to_python(resolution_json(judge_solid_resolution(
                      bd.body->mesh, bd.map->level_set(), bd.num_design_features, p))));
}

// lsmbs.geometry: the design mapped on the meshes.
void bind_geometry(py::module_& m) {
  m.def(
      "geometry",
      [](const CasePtr& cs, const py::object& design) {
        if (!cs->design) throw Error(cs->file, "/design", "the case has no design section");
        const CaseTurn turn(*cs);
        const Vec p = prepared(*cs, design);  // as `lsmbs geometry` loads the case
        ModelParams params = cs->model->params();
        std::vector<SpMat> dmu;
        cs->design->apply(p, params, &dmu);
        py::dict bodies;
        for (size_t b = 0; b < cs->design->bodies.size(); ++b) {
          const BodyDesign& bd = cs->design->bodies[b];
          const FlexibleBody& body = *bd.body;
          const Mesh2D& mesh = body.mesh;
          Mat nodes(mesh.num_nodes(), 2);
          Vec phi(mesh.num_nodes());
          const auto values = bd.map->level_set().values(p);
          for (int i = 0; i < mesh.num_nodes(); ++i) {
            nodes.row(i) = mesh.nodes[static_cast<size_t>(i)].transpose();
            phi[i] =
                bd.map->level_set().evaluate(mesh.nodes[static_cast<size_t>(i)], values, nullptr);
          }
          // cells: one array of node indices per cell (counter-clockwise); quads: the same as an
          // (elements × 4) array when every cell is a quadrilateral
          py::list cells, types;
          bool all_quads = true;
          for (const Cell& c : mesh.cells) {
            cells.append(py::array_t<int>(c.size(), c.begin()));
            types.append(element_type(c.type).name);
            all_quads = all_quads && c.size() == 4;
          }
          py::object quads = py::none();
          if (all_quads) {
            py::array_t<int> a({static_cast<py::ssize_t>(mesh.num_elements()), py::ssize_t{4}});
            auto q = a.mutable_unchecked<2>();
            for (int e = 0; e < mesh.num_elements(); ++e)
              for (int k = 0; k < 4; ++k) q(e, k) = mesh.cells[static_cast<size_t>(e)][k];
            quads = a;
          }
          Vec grad;
          const double mass = Design::mass_gradient(bd, dmu[b], params, grad);
          bodies[py::str(body.name)] =
              py::dict(py::arg("nodes") = array(nodes), py::arg("cells") = cells,
                       py::arg("cell_types") = types, py::arg("quads") = quads,
                       py::arg("mu") = array(params.fields[static_cast<size_t>(body.field)]),
                       py::arg("phi") = array(phi), py::arg("mass") = mass,
                       py::arg("mass_gradient") = array(grad),
                       py::arg("shape") = json_to_python(shape_json(bd, p, params)),
                       py::arg("resolution") = json_to_python(
                           resolution_json(judge_resolution(mesh, bd.map->level_set(), values))));
        }
        for (size_t b = 0; b < cs->design->solid_bodies.size(); ++b)
          bodies[py::str(cs->design->solid_bodies[b].body->name)] = solid_geometry(
              cs->design->solid_bodies[b], p, params, dmu[cs->design->bodies.size() + b]);
        return bodies;
      },
      py::arg("case").none(false), py::arg("design") = py::none(),
      "Per designed body: mesh nodes and cells (body frame; 'quads' as an array when all are "
      "quadrilaterals), μ_e, the nodal level set φ (material "
      "where φ > 0), the mass and its gradient, the shape (for lsmbs.export: outline, features at "
      "the design, region, node sets) and the resolution (ligaments, holes and pieces against "
      "what the mesh resolves). A solid body: nodes N × 3, cells of hex8 or tet4, the shape of "
      "its 3D features ('kind': 'solid'), and its resolution (geometry/solid_resolution.hpp)");
}

// lsmbs.verify: the verification report of a case file.
void bind_verify(py::module_& m) {
  m.def(
      "verify",
      [](const std::filesystem::path& path, const std::filesystem::path& out_dir, bool idas,
         bool mesh_study, bool overwrite, double idas_rtol, double tol_mesh) {
        return claimed(nullptr, out_dir, overwrite, false, [&](OutputClaim& claim) {
          VerifyOptions o;
          o.on_loaded = [&](const Case& cs) { claim.claim(*cs.model); };
          o.out_dir = out_dir;
          o.idas = idas;
          o.mesh_study = mesh_study;
          o.idas_rtol = idas_rtol;
          o.tol_mesh = tol_mesh;
          o.command_line = "lsmbs.verify (Python)";
          PythonRun run{py::none()};
          const VerifyResult r = run([&] { return run_verify(path, o); });
          return json_to_python(r.summary);
        });
      },
      py::arg("path"), py::arg("out_dir"), py::arg("idas") = true, py::arg("mesh_study") = true,
      py::arg("overwrite") = false, py::arg("idas_rtol") = VerifyOptions{}.idas_rtol,
      py::arg("tol_mesh") = VerifyOptions{}.tol_mesh,
      "The verification report of a case file (as `lsmbs verify`); returns its summary");
}

// lsmbs._sweep: run_sweep with Python's arguments (lsmbs.sweep in python/lsmbs/__init__.py turns
// its rows into a pandas DataFrame).
void bind_sweep(py::module_& m) {
  m.def(
      "_sweep",
      [](const CasePtr& cs, const std::vector<std::tuple<std::string, double, double, int>>& axes,
         int samples, unsigned long seed, bool gradients, const std::string& method, int jobs,
         const std::filesystem::path& out_dir, bool resume, bool overwrite,
         const py::object& progress) {
        SweepOptions o;
        for (const auto& [name, lo, hi, n] : axes) o.axes.push_back({name, lo, hi, n});
        o.samples = samples, o.seed = seed, o.gradients = gradients, o.jobs = jobs;
        if (!SensitivityOptions::parse(method, o.sensitivity.method))
          throw py::value_error("method '" + method + "': not a sensitivity method");
        o.sensitivity.threads = 1;
        o.out_dir = out_dir, o.resume = resume, o.command = "lsmbs.sweep (Python)";
        if (auto msg = o.validate(); !msg.empty()) throw py::value_error(msg);
        const CaseTurn turn(*cs);
        prepared(*cs, py::none());
        return claimed(cs->model.get(), out_dir, overwrite, resume, [&](OutputClaim&) {
          PythonRun run(progress);
          const SweepRun r = run([&] { return located(*cs, [&] { return run_sweep(*cs, o); }); });
          return py::dict(py::arg("columns") = r.columns, py::arg("rows") = r.rows,
                          py::arg("points") = r.points, py::arg("wall") = r.wall,
                          py::arg("status") = r.status, py::arg("message") = r.message,
                          py::arg("summary") = json_to_python(r.summary));
        });
      },
      py::arg("case"), py::arg("axes"), py::arg("samples"), py::arg("seed"), py::arg("gradients"),
      py::arg("method"), py::arg("jobs"), py::arg("out_dir"), py::arg("resume"),
      py::arg("overwrite"), py::arg("progress"));
}

}  // namespace lsmbs_python
