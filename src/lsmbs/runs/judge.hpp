#pragma once
// judge_design — is an optimized design a structure, or an artefact of the fixed-mesh model? Two
// checks, both after an optimization (run_optimize) and of any design on request:
//   1. resolution (geometry/resolution.hpp): ligaments, members and holes narrower than about two
//      elements, and material that falls apart into pieces, per designed body;
//   2. the load path: every condition is simulated again with the ersatz material of the void
//      made `ersatz_factor` times weaker and lighter (μ_min → μ_min · factor, the mapping's
//      μ_e = μ_min + (1 − μ_min) H (eq. 5) rescaled exactly: μ' = μ_min' + (1 − μ_min')
//      (μ − μ_min)/(1 − μ_min)). A structure's responses barely change (the void's share of the
//      stiffness is of order μ_min); a design whose parts hang on void changes by orders of
//      magnitude. A response of the objective or the constraints that changes by more than
//      `ersatz_tolerance` (relative to the larger of its value and its bound), or a re-simulation
//      that fails, flags the design.
// The verdict: sound (no flag), unresolved (parts narrower than the mesh resolves: a structure
// whose numbers are the mapping's), or not a structure (pieces, a load path through void).
// Multi-start ranks sound designs first, then unresolved ones, then those that are no structure.
// The tolerance's default, 10 %, lies between the robot arm's sound optimum (1 % change) and the
// design that the slit cuts in two (125 %; tests/integration/judge_test.cpp).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lsmbs/geometry/resolution.hpp"
#include "lsmbs/optimization/problem.hpp"
#include "lsmbs/sensitivity/conditions.hpp"

namespace lsmbs {

struct DesignJudgement {
  struct Body {
    std::string name;
    ResolutionReport resolution;
  };
  std::vector<Body> bodies;
  /// The load-path check: each response of the objective and the constraints at the design, with
  /// the ersatz material as mapped and made weaker.
  struct Response {
    std::string name;
    double value = 0, weak = 0;  ///< max over the steps of a per-step response
    double change = 0;           ///< |weak − value| / max(|value|, |bound|)
    bool flagged = false;
  };
  bool ersatz_ran = false;
  double mu_min_factor = 0;
  std::string ersatz_failure;  ///< why the weaker re-simulation failed (flags the design)
  std::vector<Response> responses;
  /// Why the design is not a structure: material in pieces, a load path through void, a
  /// re-simulation that failed.
  std::vector<std::string> structure_flags;
  /// Parts narrower than the mesh resolves (the design is a structure; its numbers are the
  /// mapping's, not the part's).
  std::vector<std::string> resolution_flags;
  enum class Verdict { kSound, kUnresolved, kNotAStructure };
  Verdict verdict() const;
  static const char* verdict_name(Verdict v);  ///< sound | unresolved | not a structure
  bool sound() const { return verdict() == Verdict::kSound; }
  std::vector<std::string> flags() const;  ///< structure flags, then resolution flags
  nlohmann::json to_json() const;
};

/// A body's resolution report as summary.json gives it (widths and positions in m, areas in m²).
nlohmann::json resolution_json(const ResolutionReport& r);

/// Judges design p of the problem's conditions with spec.judge; `run` runs the conditions'
/// simulations (a collective under MPI: every rank calls it). Only the geometric check when
/// spec.judge.ersatz is false.
DesignJudgement judge_design(const Conditions& c, const OptimizationSpec& spec, const Vec& p,
                             const ConditionExecutor& run);

}  // namespace lsmbs
