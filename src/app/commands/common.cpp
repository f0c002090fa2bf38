#include "app/commands/common.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>

#include "app/commands/commands.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/core/text.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/sha256.hpp"
#include "lsmbs/runs/simulate.hpp"

namespace lsmbs::app {

// "name=value" overrides of design variables.
std::pair<std::string, double> parse_set(const std::string& s) {
  const auto eq = s.find('=');
  if (eq == std::string::npos) throw lsmbs::Error("--set " + s + ": expected name=value");
  const auto v = lsmbs::parse_finite_double(std::string_view(s).substr(eq + 1));
  if (!v) throw lsmbs::Error("--set " + s + ": expected a finite number after '='");
  return {s.substr(0, eq), *v};
}

std::string set_target(const std::string& s, const nlohmann::json& doc) {
  const auto eq = s.find('=');
  if (eq == std::string::npos) return {};
  const std::string left = s.substr(0, eq);
  if (!left.empty() && left[0] == '/') {
    try {  // the pointer as the loader reads it (escapes ~0 ~1 spelled one way)
      return nlohmann::json::json_pointer(left).to_string();
    } catch (const nlohmann::json::exception&) {
      return {};  // not a pointer: the loader says so
    }
  }
  if (!doc.is_object() || !doc.contains("design") || !doc["design"].is_object() ||
      !doc["design"].contains("variables") || !doc["design"]["variables"].is_array())
    return {};
  const auto& vars = doc["design"]["variables"];
  for (size_t i = 0; i < vars.size(); ++i)
    if (vars[i].is_object() && vars[i].contains("name") && vars[i]["name"] == left)
      return "/design/variables/" + std::to_string(i) + "/initial";
  return {};
}

bool pointers_overlap(const std::string& a, const std::string& b) {
  if (a.empty() || b.empty()) return false;
  auto holds = [](const std::string& outer, const std::string& inner) {
    return inner.size() > outer.size() && inner.compare(0, outer.size(), outer) == 0 &&
           inner[outer.size()] == '/';
  };
  return a == b || holds(a, b) || holds(b, a);
}

void check_sets(const std::string& case_file, const std::vector<std::string>& sets) {
  // Every --set reaches summary.json (JSON text is UTF-8) and the case document: bytes that are
  // not UTF-8 are refused here, before the run, not when the summary is written after it.
  for (const auto& s : sets)
    if (const size_t at = lsmbs::invalid_utf8_at(s); at != std::string::npos)
      throw lsmbs::Error("--set " + lsmbs::shown(s) + ": not valid UTF-8 text (byte " +
                         std::to_string(at + 1) + "); case values and names are UTF-8 (JSON text)");
  // Two --set of one value: the later replaced the earlier and summary.json kept only it. Each
  // value may be given once; a value inside another one's object counts as the same value.
  if (sets.size() < 2) return;
  nlohmann::json doc;  // for the design variables of name=value (their initial values' paths)
  if (std::any_of(sets.begin(), sets.end(),
                  [](const std::string& s) { return s.empty() || s[0] != '/'; })) {
    try {
      std::ifstream f(case_file, std::ios::binary);
      const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
      doc = lsmbs::parse_json_document(text, case_file);
    } catch (const std::exception&) {  // the loader reports an unreadable case
    }
  }
  std::vector<std::string> target;
  for (const auto& s : sets) target.push_back(set_target(s, doc));
  for (size_t j = 1; j < sets.size(); ++j)
    for (size_t i = 0; i < j; ++i)
      if (pointers_overlap(target[i], target[j])) {
        const bool same = target[i] == target[j];
        const std::string& outer = target[i].size() <= target[j].size() ? target[i] : target[j];
        const std::string& inner = target[i].size() <= target[j].size() ? target[j] : target[i];
        throw lsmbs::Error("--set " + sets[i] + " and --set " + sets[j] +
                           (same ? " set the same value (" + outer + ")"
                                 : " overlap (" + inner + " is part of " + outer + ")") +
                           ": the later one would replace the earlier without a word; give each "
                           "value once");
      }
}

// A run that ends with an exception once it has started (a numerical failure raised deep inside,
// memory exhausted, an internal error) leaves a summary.json with status partial and the reason,
// replacing any earlier summary: exit 1 always comes with results flagged as partial.
void flag_failed_run(const std::string& out, const std::string& cmdline,
                     const std::string& case_file, const std::string& what,
                     const std::string& status) {
  try {
    std::filesystem::create_directories(out);
    std::string sha;  // of the case file's bytes, as a complete run records it
    if (std::ifstream in(case_file, std::ios::binary); in) {
      const std::string text((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
      sha = lsmbs::sha256_hex(text);
    }
    nlohmann::json S = lsmbs::provenance(cmdline, case_file, sha);
    S["status"] = status;
    S["failure"] = what;
    // what the run wrote before it failed is its own: a later --overwrite replaces it
    auto files = lsmbs::files_written_under(out);
    files.erase(std::remove(files.begin(), files.end(), "summary.json"), files.end());
    files.push_back("summary.json");
    S["files"] = files;
    lsmbs::write_json_atomic(out + "/summary.json", S);
  } catch (const std::exception&) {  // the folder cannot be written: the message on stderr remains
  }
}

void claim_output(const CommonArgs& c, const lsmbs::Model& model) {
  if (!c.replaced) return;
  *c.replaced =
      lsmbs::claim_output_folder(c.out, c.overwrite, c.resume, lsmbs::planned_outputs(model));
}

void check_gradient_check_options(const lsmbs::GradientCheckOptions& o) {
  if (auto msg = o.validate(); !msg.empty())
    throw lsmbs::Error(lsmbs::rename_fields(msg, {{"delta", "--check-delta"},
                                                  {"seed", "--check-seed"},
                                                  {"warn", "--check-warn"},
                                                  {"fail", "--check-fail"}}));
}

// IDAS tolerances from the command line: checked before anything runs
void check_idas_tolerances(double rtol, double atol) {
  if (const auto msg = lsmbs::idas_tolerance_error(rtol, atol); !msg.empty()) {
    const bool r = msg.rfind("rtol", 0) == 0;
    throw lsmbs::Error("--" + msg.substr(0, 4) + " " + std::to_string(r ? rtol : atol) +
                       msg.substr(4));
  }
}

// --set /pointer=value: a value of the case document by JSON path; the value is JSON (a number,
// true, [1, 2], "text") or else taken as a string (--set /simulation/newton=modified).
lsmbs::CaseOverride parse_override(const std::string& s) {
  const auto eq = s.find('=');
  if (eq == std::string::npos) throw lsmbs::Error("--set " + s + ": expected /json/path=value");
  lsmbs::CaseOverride o;
  o.pointer = s.substr(0, eq);
  o.origin = "--set " + s;
  const std::string v = s.substr(eq + 1);
  if (v.empty()) throw lsmbs::Error("--set " + s + ": expected a value after '='");
  try {  // JSON as a case file is read: a key given twice is refused (the last one won silently)
    o.value = lsmbs::parse_json_document(v, o.origin);
  } catch (const nlohmann::json::exception&) {
    o.value = v;
  }
  return o;
}

lsmbs::Case load_case_with_sets(const std::string& file, const std::vector<std::string>& sets,
                                bool design_as_initial) {
  return lsmbs::load_case(file, case_overrides(file, sets, design_as_initial));
}

std::vector<lsmbs::CaseOverride> case_overrides(const std::string& file,
                                                const std::vector<std::string>& sets,
                                                bool design_as_initial) {
  check_sets(file, sets);
  std::vector<lsmbs::CaseOverride> overrides;
  nlohmann::json doc;  // read only to find design variables by name (design_as_initial)
  for (const auto& s : sets) {
    if (!s.empty() && s[0] == '/') {
      overrides.push_back(parse_override(s));
      continue;
    }
    if (!design_as_initial) continue;  // a design point: design_point()
    const auto [name, value] = parse_set(s);
    if (doc.is_null()) doc = lsmbs::load_case(file).raw;  // validates the case as it is
    int k = -1;
    if (doc.contains("design"))
      for (size_t i = 0; i < doc["design"]["variables"].size(); ++i)
        if (doc["design"]["variables"][i]["name"] == name) k = static_cast<int>(i);
    if (k < 0)
      throw lsmbs::Error(
          "--set " + s + ": unknown design variable '" + name + "'" +
          (name.find('/') != std::string::npos ? " (a JSON path starts with /)" : ""));
    overrides.push_back(
        {"/design/variables/" + std::to_string(k) + "/initial", value, "--set " + s});
  }
  return overrides;
}

lsmbs::Vec design_point(const lsmbs::Case& cs, const std::vector<std::string>& sets) {
  lsmbs::Vec p = cs.design->initial();
  for (const auto& s : sets) {
    if (!s.empty() && s[0] == '/') continue;  // a JSON-path override (load_case_with_sets)
    const auto [name, parsed] = parse_set(s);
    const int k = cs.design->variable_index(name);
    if (k < 0)
      throw lsmbs::Error(
          "--set " + s + ": unknown design variable '" + name + "'" +
          (name.find('/') != std::string::npos ? " (a JSON path starts with /)" : ""));
    const auto& v = cs.design->variables[k];
    const double value = cs.design->snap_to_bounds(k, parsed);
    if (!(value >= v.lower && value <= v.upper))
      throw lsmbs::Error("--set " + s + ": outside the bounds [" + std::to_string(v.lower) + ", " +
                         std::to_string(v.upper) + "] of design variable '" + name +
                         "' (the case validates its features over these bounds; widen them in the "
                         "case to go further)");
    p[k] = value;
  }
  return p;
}

void print_gradient_check(const lsmbs::GradientCheckResult& c,
                          const lsmbs::GradientCheckOptions& o) {
  std::printf(
      "  gradient check (central differences along a random direction, 2 simulations): %s\n",
      c.verdict(o).c_str());
  if (!c.ok) {
    std::printf("    %s\n", c.message.c_str());
    return;
  }
  for (const auto& e : c.entries)
    std::printf("    %-24s fd %+.6e  method %+.6e  relative disagreement %.2e\n",
                e.response.c_str(), e.finite_difference, e.method, e.relative_error);
}

}  // namespace lsmbs::app
