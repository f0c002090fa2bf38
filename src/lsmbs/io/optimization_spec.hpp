#pragma once
// Parses and validates a case's "optimization" section (docs/case-format.md) with JSON paths.
#include "lsmbs/io/case.hpp"
#include "lsmbs/optimization/problem.hpp"

namespace lsmbs {
OptimizationSpec parse_optimization(const Case& cs);
}
