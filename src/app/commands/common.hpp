#pragma once
// What the commands share: the output folder's checks, --set parsing, the failure flag.
#include <string>
#include <utility>
#include <vector>

#include "lsmbs/io/case.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"

namespace lsmbs::app {

struct CommonArgs;

/// "name=value" override of a design variable.
std::pair<std::string, double> parse_set(const std::string& s);
/// "--set /json/pointer=value" (the value parsed as JSON, else a string).
CaseOverride parse_override(const std::string& s);
/// The JSON pointer of the value that a --set argument changes: its own for /pointer=value; for
/// name=value the design variable's initial value, /design/variables/k/initial (k its index in
/// the case document `doc`). Empty when unknown (the loader then reports the argument).
std::string set_target(const std::string& s, const nlohmann::json& doc);
/// Whether two JSON pointers address the same value or one holds the other.
bool pointers_overlap(const std::string& a, const std::string& b);
/// Refuses --set arguments that are not UTF-8, and two that set the same value (or one inside
/// the other's): the later would replace the earlier without a word.
void check_sets(const std::string& case_file, const std::vector<std::string>& sets);
/// The case file with the --set /json/pointer=value overrides applied. The short form name=value
/// sets a design variable: the design point (design_point) or, with `design_as_initial`
/// (optimize), the variable's initial value.
Case load_case_with_sets(const std::string& file, const std::vector<std::string>& sets,
                         bool design_as_initial = false);
/// The overrides load_case_with_sets applies (checked the same way).
std::vector<CaseOverride> case_overrides(const std::string& file,
                                         const std::vector<std::string>& sets,
                                         bool design_as_initial);
/// The case's initial design with the --set overrides (each checked against its bounds).
Vec design_point(const Case& cs, const std::vector<std::string>& sets);
/// Claims the output folder for a run of `model` once its case has loaded (io/output_folder.hpp:
/// an earlier run is replaced only with --overwrite, files no summary lists are never touched);
/// the earlier run is kept in *c.replaced until the run is past its input checks.
void claim_output(const CommonArgs& c, const Model& model);
/// A run that failed with an exception once started leaves summary.json with status partial,
/// listing the files it wrote.
void flag_failed_run(const std::string& out, const std::string& cmdline,
                     const std::string& case_file, const std::string& what,
                     const std::string& status = "partial");
/// The gradient check's options from the command line, checked before anything runs; a message
/// names the flag (--check-fail), not the library's field.
void check_gradient_check_options(const GradientCheckOptions& o);
/// IDAS tolerances from the command line, checked before anything runs.
void check_idas_tolerances(double rtol, double atol);
void print_gradient_check(const GradientCheckResult& c, const GradientCheckOptions& o);

}  // namespace lsmbs::app
