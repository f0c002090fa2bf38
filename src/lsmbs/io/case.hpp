#pragma once
// Case — everything a JSON case file defines: the model, the initial state, the integrator
// options, the measures recorded and the responses reported. The format is documented in
// docs/case-format.md. Loading validates every field and throws lsmbs::Error (file, JSON
// path, what was expected) before anything is written.
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lsmbs/core/error.hpp"
#include "lsmbs/mbs/model_builder.hpp"
#include "lsmbs/mbs/time_law.hpp"
#include "lsmbs/sensitivity/study.hpp"

namespace lsmbs {

struct OutputSpec {
  int csv_stride = 1;  ///< every n-th grid step in history.csv
  int vtu_stride = 0;  ///< every n-th grid step as VTU (0: none)
};

/// What the start checks (prepare_case) need from the building of a case, kept so that they can
/// run again on a case changed after loading (from Python): the state as the case places the
/// bodies, the velocities it gives, and which entry of the document made each entity.
struct CaseStart {
  State placed;  ///< t = 0, positions and given velocities as placed (before the projection)
  std::vector<char> held_velocities;            ///< per unknown: its initial velocity was given
  std::vector<GivenVelocity> given_velocities;  ///< per body that gives velocities
  std::map<std::string, std::string> paths;     ///< JSON path of each body, joint and force
  std::vector<std::string> force_owners;        ///< per force element: its body or force entry
  std::map<std::string, std::vector<int>> entity_parameters;  ///< the parameters of each entry
};

/// A case file: the Study it defines (model, initial state, options, measures, responses, design)
/// and what only the file has (its name, hash and document, output strides, the optimization
/// section, names of drivers and joints).
struct Case : Study {
  std::string file;  ///< path as given
  std::string name;
  std::string sha256;  ///< of the case file's bytes
  nlohmann::json raw;
  /// simulation.check_constraints: refuse redundant or conflicting constraints at load time
  /// (false only for models that are evaluated, never integrated, e.g. derivative tests).
  bool check_constraints = true;
  OutputSpec output;
  std::map<std::string, std::shared_ptr<const TimeLaw>> drivers;  ///< by driver name
  std::map<std::string, std::vector<int>> joint_rows;             ///< constraint rows by joint name
  nlohmann::json optimization;  ///< the "optimization" section (parsed by parse_optimization)
  /// Values changed before loading (--set /pointer=value): JSON pointer -> value; an empty object
  /// when none. `sha256` stays the file's; summaries record both.
  nlohmann::json overrides = nlohmann::json::object();
  CaseStart start;
  /// Files the case reads besides itself (tables, meshes, initial states): path as resolved ->
  /// SHA-256 of its bytes when loaded. Summaries record them beside case_sha256.
  std::map<std::string, std::string> input_files;
};

/// provenance() of a run of `cs` (its file and hash) with the files it reads (input_files).
nlohmann::json case_provenance(const std::string& command, const Case& cs);

/// A change of one value of the case document before it is loaded: `lsmbs … --set
/// /simulation/h=1e-3`, `--set /bodies/1/material/E=70e9`. The pointer's parent must exist (an
/// object, or an array holding that index); the loader then checks the changed document as any
/// case file, and an error at the changed value says it came from the override.
struct CaseOverride {
  std::string pointer;   ///< JSON pointer (RFC 6901)
  nlohmann::json value;  ///< any JSON value
  std::string origin;    ///< how it was given, for messages ("--set /simulation/h=1e-3")
};

/// The error of the library (by subject) located in the case file: "design" → /design,
/// "responses" → /output/responses, "optimization.objective" → /optimization/objective, … .
Error locate(const std::string& case_file, const SetupError& e);

/// The start checks of a case, the ones a case file meets after its model is built: the simulation
/// options, independent constraints at t = 0, a time step of the run in every response window,
/// finite element forces and iteration matrix at the start (with the design `design`, or the
/// initial design when null, written into the model's parameters), given velocities that the
/// joints allow, bodies placed where the joints and drivers put them, and finite measures at t = 0.
/// Sets `cs.initial` (the placed state, projected onto the constraints when velocities are given).
/// The loader runs them on every case; a case changed after loading (simulation options or model
/// parameters set from Python) runs them again before each run, and so meets the same messages.
/// Throws Error (file, JSON path of the entry at fault, what is wrong).
void prepare_case(Case& cs, const Vec* design = nullptr);

/// What a resumed optimization must find unchanged, hashed (SHA-256, hex): the case file's bytes,
/// its overrides, the simulation options and every model parameter that no design variable sets
/// (what Python may change after loading). The command line and Python use this one hash, so a
/// run started in one resumes in the other.
std::string resume_hash(const Case& cs);

/// The JSON path in the case document of model parameter `i` ("crank.mass" → /bodies/0/mass,
/// "rod.E" → /bodies/1/material/E); "" when the case does not say where its entity is.
std::string parameter_json_path(const Case& cs, int i);

/// Loads and validates a case file (paths inside are relative to its folder).
Case load_case(const std::string& path);
/// Same, with values of the document changed first (in order).
Case load_case(const std::string& path, const std::vector<CaseOverride>& overrides);
/// Same from an already parsed document (tests); `base_dir` resolves relative file names.
Case load_case_json(const nlohmann::json& j, const std::string& file_label,
                    const std::string& base_dir);

}  // namespace lsmbs
