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
#include "lsmbs/sensitivity/conditions.hpp"
#include "lsmbs/sensitivity/study.hpp"

namespace lsmbs {

struct OutputSpec {
  int csv_stride = 1;  ///< every n-th grid step in history.csv
  int vtu_stride = 0;  ///< every n-th grid step as VTU (0: none)
};

struct Case;

/// A service condition of a case (docs/case-format.md, "conditions"): the case's document with the
/// condition's values set, loaded as a case of its own.
struct CaseCondition {
  std::string name;
  std::unique_ptr<Case> cs;
  std::vector<std::string> set;  ///< the JSON pointers it sets (array entries by index)
};

/// A case file: the Study it defines (model, initial state, options, measures, responses, design)
/// and what only the file has (its name, hash and document, output strides, the optimization
/// section, names of drivers and joints).
struct Case : Study {
  std::string file;      ///< path as given
  std::string base_dir;  ///< the folder relative file names of the document are read from
  std::string name;
  std::string sha256;  ///< of the case file's bytes
  nlohmann::json raw;
  OutputSpec output;
  std::map<std::string, std::shared_ptr<const TimeLaw>> drivers;  ///< by driver name
  std::map<std::string, std::vector<int>> joint_rows;             ///< constraint rows by joint name
  nlohmann::json optimization;  ///< the "optimization" section (parsed by parse_optimization)
  /// Values changed before loading (--set /pointer=value): JSON pointer -> value; an empty object
  /// when none. `sha256` stays the file's; summaries record both.
  nlohmann::json overrides = nlohmann::json::object();
  /// The JSON path of each body, joint and force by name (and of each entry of an initial state
  /// that gives velocities): where an error of the start checks that names an entity points.
  std::map<std::string, std::string> paths;
  /// Service conditions (empty: the case is its one condition). The case itself is the base they
  /// are made from: its model is checked as any case's, and its design is the conditions' design.
  std::vector<CaseCondition> conditions;
  /// Responses combined from others ("combined": sums, KS envelopes, exact maxima).
  std::vector<ResponseCombination> combined;
  /// Files the case reads besides itself (tables, meshes, initial states): path as resolved ->
  /// SHA-256 of its bytes when loaded. Summaries record them beside case_sha256.
  std::map<std::string, std::string> input_files;
};

/// The studies a run of the case evaluates: its conditions, or the case itself, with the
/// combinations of their responses.
Conditions conditions_of(const Case& cs);
/// Whether the condition sets a value of the design (/design/geometry/<entry>/offset): a variant
/// of the design, whose state-independent responses (its mass) are its own.
bool is_design_variant(const CaseCondition& c);

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
/// Same, and an error that names an entity (a body, joint or force) at that entity's entry
/// (Case::paths), e.g. body 'crank' → /bodies/1, its field "velocity" → /bodies/1/velocity.
Error locate(const Case& cs, const SetupError& e);

/// The start checks of a case (Study::prepare) with their errors located in the case file: the
/// loader runs them on every case; a case changed after loading (simulation options or model
/// parameters set from Python) runs them again before each run, and so meets the same messages.
/// Throws Error (file, JSON path of the entry at fault, what is wrong).
void prepare_case(Case& cs, const Vec* design = nullptr);

/// The base case's simulation options and model parameters, as Python may have changed them,
/// copied into each service condition, except those the condition sets itself; then each
/// condition's start checks (prepare_case) at `design`.
void prepare_conditions(Case& cs, const Vec* design = nullptr);

/// What a resumed optimization must find unchanged, hashed (SHA-256, hex): the case file's bytes,
/// its overrides, the simulation options and every model parameter that no design variable sets
/// (what Python may change after loading). The command line and Python use this one hash, so a
/// run started in one resumes in the other.
std::string resume_hash(const Case& cs);

/// The JSON path in the case document of model parameter `i` ("crank.mass" → /bodies/0/mass,
/// "rod.E" → /bodies/1/material/E); "" when the case does not say where its entity is.
std::string parameter_json_path(const Case& cs, int i);

/// A JSON pointer into `doc` whose tokens may name an entry of an array of named entries
/// (/forces/payload/mass), as the same pointer with indices (/forces/2/mass). Throws Error
/// (`what` names the pointer's origin) for an entry or a parent that does not exist.
std::string indexed_pointer(const nlohmann::json& doc, const std::string& pointer,
                            const std::string& what);

/// The case's document as it stands: the file's (with its --set overrides), the simulation
/// options and the model parameters as Python may have changed them (those no design variable
/// sets). Loading it gives this case again.
nlohmann::json current_document(const Case& cs);

/// Loads and validates a case file (paths inside are relative to its folder).
Case load_case(const std::string& path);
/// Same, with values of the document changed first (in order).
Case load_case(const std::string& path, const std::vector<CaseOverride>& overrides);
/// Same from an already parsed document (tests); `base_dir` resolves relative file names.
Case load_case_json(const nlohmann::json& j, const std::string& file_label,
                    const std::string& base_dir);

}  // namespace lsmbs
