#pragma once
// Parses and validates a case's "optimization" section (docs/case-format.md) with JSON paths.
#include "lsmbs/io/case.hpp"
#include "lsmbs/optimization/problem.hpp"

namespace lsmbs {
OptimizationSpec parse_optimization(const Case& cs);
/// Replaces the case's optimizer by one named outside the case (`origin`: "--optimizer mma", or
/// Python's "optimizer='mma'"); an empty name keeps the case's. An unknown name is an Error at
/// /optimization/optimizer; a case that sets a move_limit keeps mma-svanberg, the only optimizer
/// that has one (Error "<origin>: …").
void set_optimizer(OptimizationSpec& spec, const Case& cs, const std::string& optimizer,
                   const std::string& origin);
}  // namespace lsmbs
