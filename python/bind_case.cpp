#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "lsmbs/core/version.hpp"
#include "lsmbs/io/json_reader.hpp"
#include "lsmbs/io/model_kinds.hpp"
#include "python/support.hpp"

namespace lsmbs_python {

// lsmbs.Error (file, json_path, reason), lsmbs.NumericalFailure, lsmbs.GradientCheckFailed.
void bind_errors(py::module_& m) {
  static py::exception<Error> error_type(m, "Error", PyExc_ValueError);
  static py::exception<NumericalFailure> failure_type(m, "NumericalFailure", PyExc_RuntimeError);
  g_check_failed =
      PyErr_NewException("lsmbs._lsmbs.GradientCheckFailed", failure_type.ptr(), nullptr);
  m.attr("GradientCheckFailed") = py::handle(g_check_failed);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      py::object exc = py::reinterpret_borrow<py::object>(error_type.ptr())(e.what());
      exc.attr("file") = e.file();
      exc.attr("json_path") = e.json_path();
      std::string reason = e.what();  // without the "file: path: " prefix
      for (const std::string& part : {e.file(), e.json_path()})
        if (!part.empty() && reason.rfind(part + ": ", 0) == 0) reason.erase(0, part.size() + 2);
      exc.attr("reason") = reason;
      PyErr_SetObject(error_type.ptr(), exc.ptr());
    } catch (const NumericalFailure& e) {
      PyErr_SetString(failure_type.ptr(), e.what());
    }
  });
}

// lsmbs.SimulationOptions: a case's generalized-α options.
void bind_options(py::module_& m) {
  py::class_<GeneralizedAlphaOptions>(m, "SimulationOptions",
                                      "Generalized-α options of a case (its 'simulation' section)")
      .def_readwrite("h", &GeneralizedAlphaOptions::h, "time step [s]")
      .def_readwrite("t_end", &GeneralizedAlphaOptions::t_end, "final time [s]")
      .def_readwrite("rho_inf", &GeneralizedAlphaOptions::rho_inf, "spectral radius at infinity")
      .def_readwrite("tol_r", &GeneralizedAlphaOptions::tol_r)
      .def_readwrite("tol_phi", &GeneralizedAlphaOptions::tol_phi)
      .def_readwrite("tol_q", &GeneralizedAlphaOptions::tol_q)
      .def_readwrite("max_iter", &GeneralizedAlphaOptions::max_iter)
      .def_readwrite("min_iter", &GeneralizedAlphaOptions::min_iter)
      .def_readwrite("max_halvings", &GeneralizedAlphaOptions::max_halvings)
      .def_readwrite("consistent_start", &GeneralizedAlphaOptions::consistent_start)
      .def_readwrite("project_initial", &GeneralizedAlphaOptions::project_initial)
      .def_readwrite("k", &GeneralizedAlphaOptions::k,
                     "constraint scaling of eq. (7); 0: automatic")
      .def_readwrite("zeta", &GeneralizedAlphaOptions::zeta, "penalty of eq. (7); 0: automatic")
      .def_property(
          "newton",
          [](const GeneralizedAlphaOptions& o) {
            return std::string(GeneralizedAlphaOptions::newton_name(o.newton));
          },
          [](GeneralizedAlphaOptions& o, const std::string& n) {
            using N = GeneralizedAlphaOptions::Newton;
            if (n == "full")
              o.newton = N::kFull;
            else if (n == "modified")
              o.newton = N::kModified;
            else if (n == "modified_across_steps")
              o.newton = N::kModifiedAcrossSteps;
            else
              throw py::value_error("newton '" + n +
                                    "': expected full, modified or modified_across_steps");
          })
      .def_property(
          "ordering",
          [](const GeneralizedAlphaOptions& o) {
            return std::string(SparseLU::ordering_name(o.ordering));
          },
          [](GeneralizedAlphaOptions& o, const std::string& n) {
            if (n == "amd")
              o.ordering = SparseLU::Ordering::kAmd;
            else if (n == "nested_dissection")
              o.ordering = SparseLU::Ordering::kNestedDissection;
            else
              throw py::value_error("ordering '" + n + "': expected amd or nested_dissection");
          })
      .def_property(
          "linear_solver",
          [](const GeneralizedAlphaOptions& o) {
            return std::string(SparseLU::solver_name(o.linear_solver));
          },
          [](GeneralizedAlphaOptions& o, const std::string& n) {
            using S = SparseLU::Solver;
            if (n == "amg" && !SparseLU::amg_available())
              throw py::value_error(
                  "linear_solver 'amg': this build of lsmbs has no hypre (libhypre-dev)");
            if (n == "auto" || n == "klu" || n == "umfpack" || n == "amg")
              o.linear_solver = n == "auto"      ? S::kAuto
                                : n == "klu"     ? S::kKlu
                                : n == "umfpack" ? S::kUmfpack
                                                 : S::kAmg;
            else
              throw py::value_error("linear_solver '" + n +
                                    "': expected auto, klu, umfpack or amg");
          })
      .def_readwrite("force_floor", &GeneralizedAlphaOptions::force_floor)
      .def("validate", &GeneralizedAlphaOptions::validate,
           "'' when valid, else 'field: what is expected'")
      .def("to_dict", [](const GeneralizedAlphaOptions& o) { return json_to_python(o); })
      .def("__repr__", [](const GeneralizedAlphaOptions& o) {
        return "SimulationOptions(" + nlohmann::json(o).dump() + ")";
      });
}

// lsmbs.Parameters: the model's named scalar parameters.
void bind_parameters(py::module_& m) {
  py::class_<Parameters>(m, "Parameters", "The model's named scalar parameters ('body.E', …)")
      .def("__getitem__",
           [](const Parameters& p, const std::string& name) {
             return p.cs->model->params().scalars[static_cast<size_t>(p.index(name))];
           })
      .def("__setitem__",
           [](Parameters& p, const std::string& name, double value) {
             const int i = p.index(name);
             if (p.cs->design)
               for (const auto& b : p.cs->design->bindings)
                 if (b.parameter == i)
                   throw py::value_error(
                       "model parameter '" + name + "' is set by design variable '" +
                       p.cs->design->variables[static_cast<size_t>(b.variable)].name +
                       "': change the design instead (design=…)");
             // at the parameter's place in the case file, in the loader's words (lsmbs.Error)
             if (auto msg = ModelBuilder::check_parameter_value(name, value); !msg.empty())
               throw Error(p.cs->file, parameter_json_path(*p.cs, i),
                           msg + " (model parameter '" + name + "' = " + exact(value) +
                               ", set from Python)");
             const CaseTurn turn(*p.cs);  // not under a run of another thread
             p.cs->model->params().scalars[static_cast<size_t>(i)] = value;
           })
      .def("__contains__",
           [](const Parameters& p, const std::string& name) {
             return p.cs->model->parameter_index(name) >= 0;
           })
      .def("__len__", [](const Parameters& p) { return p.cs->model->parameter_names().size(); })
      .def("keys", [](const Parameters& p) { return p.cs->model->parameter_names(); })
      .def("__iter__",
           [](const Parameters& p) { return py::iter(py::cast(p.cs->model->parameter_names())); })
      .def("to_dict", [](const Parameters& p) {
        py::dict d;
        const auto& names = p.cs->model->parameter_names();
        for (size_t i = 0; i < names.size(); ++i)
          d[py::str(names[i])] = p.cs->model->params().scalars[i];
        return d;
      });
}

// lsmbs.Case, load_case and the builder's _load_case_text.
void bind_case(py::module_& m) {
  py::class_<Case, CasePtr>(m, "Case", "A case loaded from JSON (docs/case-format.md)")
      .def_readonly("name", &Case::name)
      .def_readonly("file", &Case::file)
      .def_readonly("sha256", &Case::sha256)
      .def_property(
          "simulation", [](Case& c) -> GeneralizedAlphaOptions& { return c.simulation; },
          [](Case& c, const GeneralizedAlphaOptions& o) {
            const CaseTurn turn(c);  // not under a run of another thread
            c.simulation = o;
          },
          py::return_value_policy::reference_internal)
      .def_property_readonly("parameters", [](const CasePtr& c) { return Parameters{c}; })
      .def_property_readonly("variables",
                             [](const Case& c) {
                               std::vector<std::string> v;
                               if (c.design)
                                 for (const auto& x : c.design->variables) v.push_back(x.name);
                               return v;
                             })
      .def_property_readonly(
          "initial_design",
          [](const Case& c) { return c.design ? array(c.design->initial()) : array(Vec()); })
      .def_property_readonly(
          "lower", [](const Case& c) { return c.design ? array(c.design->lower()) : array(Vec()); })
      .def_property_readonly(
          "upper", [](const Case& c) { return c.design ? array(c.design->upper()) : array(Vec()); })
      .def_property_readonly(
          "responses", [](const Case& c) { return conditions_of(c).response_names(); },
          "the responses a run reports: with service conditions '<condition>.<response>' (a "
          "state-independent one once, unprefixed) and the combined ones")
      .def_property_readonly(
          "conditions",
          [](const Case& c) {
            std::vector<std::string> v;
            for (const auto& k : c.conditions) v.push_back(k.name);
            return v;
          },
          "the names of the case's service conditions (empty: none)")
      .def_property_readonly("measures", &Case::measure_columns)
      .def_property_readonly("dofs", [](const Case& c) { return c.model->nq(); })
      .def_property_readonly("constraints", [](const Case& c) { return c.model->nc(); })
      .def("__repr__", [](const Case& c) {
        return "<lsmbs.Case '" + c.name + "' from " + c.file + ": " +
               std::to_string(c.model->nq()) + " DOFs, " +
               std::to_string(c.design ? c.design->size() : 0) + " design variables>";
      });

  m.def(
      "load_case",
      [](const py::object& path) {
        return std::make_shared<Case>(
            load_case(py::str(py::module_::import("os").attr("fspath")(path))));
      },
      py::arg("path"), "Loads and validates a case file (raises lsmbs.Error naming the JSON path)");

  m.def(
      "_load_case_text",
      [](const std::string& text, const std::string& label, const std::string& base_dir) {
        nlohmann::json j;
        try {
          j = parse_json_document(text, label);
        } catch (const nlohmann::json::exception& e) {
          throw Error(label, "", std::string("invalid JSON: ") + e.what());
        }
        auto cs = std::make_shared<Case>(load_case_json(j, label, base_dir));
        cs->sha256 = sha256_hex(text);  // as load_case hashes the file's bytes
        return cs;
      },
      py::arg("text"), py::arg("label"), py::arg("base_dir"),
      "A case from the text of a case document (lsmbs.ModelBuilder.build); the hash is the "
      "text's, as if it were a file");
}

// A table of model kinds as Python dicts: {section, type, doc, keys: [{name, type, required,
// positional, python_default, doc}]}.
py::list kinds_to_python(const std::vector<ModelKind>& kinds) {
  py::list out;
  for (const ModelKind& k : kinds) {
    py::list keys;
    for (const KindKey& key : k.keys)
      keys.append(py::dict(
          py::arg("name") = key.name, py::arg("type") = std::string(key_type_name(key.type)),
          py::arg("required") = key.required, py::arg("positional") = key.positional,
          py::arg("python_default") =
              key.python_default.empty()
                  ? py::object(py::none())
                  : json_to_python(nlohmann::json::parse(key.python_default)),
          py::arg("doc") = key.doc));
    out.append(py::dict(py::arg("section") = k.section, py::arg("type") = k.type,
                        py::arg("doc") = k.doc, py::arg("keys") = keys));
  }
  return out;
}

// lsmbs.model_kinds() and lsmbs.spatial_model_kinds(): the tables of joints, forces, measures
// and features (io/model_kinds.hpp), from which python/lsmbs/builder.py makes the builders'
// methods.
void bind_model_kinds(py::module_& m) {
  m.def(
      "model_kinds", [] { return kinds_to_python(model_kinds()); },
      "The joints, forces, measures and features of the case format, with their keys: a list of "
      "{section, type, doc, keys: [{name, type, required, positional, python_default, doc}]}");
  m.def(
      "spatial_model_kinds", [] { return kinds_to_python(spatial_model_kinds()); },
      "The joints, forces and measures of spatial cases (\"dimension\": 3), as model_kinds()");
}

}  // namespace lsmbs_python
