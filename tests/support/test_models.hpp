#pragma once
// Helpers for tests: build a Case from an inline JSON document, run it, dense matrices of
// small models (allowed in tests of tiny models only).
#include <nlohmann/json.hpp>

#include "lsmbs/io/case.hpp"
#include "lsmbs/io/simulation_run.hpp"

namespace lsmbs::test {

inline Case make_case(const nlohmann::json& j) { return load_case_json(j, "<test>", LSMBS_SOURCE_DIR); }

inline Mat dense_iteration_matrix(const Model& m, const State& s, const Coefficients& c, double k, double zeta) {
  std::vector<double> vals;
  m.iteration_matrix(s, m.params(), c, k, zeta, vals);
  return Mat(m.assembler().to_sparse(vals));
}

/// Relative difference ‖a − b‖∞ / max(‖b‖∞, floor).
inline double rel_diff(const Mat& a, const Mat& b, double floor = 1e-300) {
  return (a - b).lpNorm<Eigen::Infinity>() / std::max(b.lpNorm<Eigen::Infinity>(), floor);
}

}  // namespace lsmbs::test
