#pragma once
// Helpers for tests: build a Case from an inline JSON document, and dense matrices of small
// models (allowed in tests of tiny models only): the iteration matrix S(c_a, c_v, c_q) of
// eq. (20) and its blocks M, C_t, K_t extracted from it.
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "lsmbs/io/case.hpp"
#include "lsmbs/runs/simulate.hpp"

namespace lsmbs::test {

inline Case make_case(const nlohmann::json& j) {
  return load_case_json(j, "<test>", LSMBS_SOURCE_DIR);
}

/// The case's measure of that name (throws if there is none).
inline const Measure& measure(const Case& cs, const std::string& name) {
  for (const auto& m : cs.measures)
    if (m->name() == name) return *m;
  throw std::runtime_error("no measure " + name);
}

inline SpMat sparse_iteration_matrix(const Model& m, const State& s, const Coefficients& c,
                                     double k, double zeta) {
  std::vector<double> vals;
  m.iteration_matrix(s, m.params(), c, k, zeta, vals);
  return m.assembler().to_sparse(vals);
}

inline Mat dense_iteration_matrix(const Model& m, const State& s, const Coefficients& c, double k,
                                  double zeta) {
  return Mat(sparse_iteration_matrix(m, s, c, k, zeta));
}

/// M = ∂r/∂q̈ (nq × nq, sparse): S(1, 0, 0) − S(0, 0, 0).
inline SpMat sparse_mass_matrix(const Model& m, const State& s) {
  const SpMat d = sparse_iteration_matrix(m, s, {1, 0, 0}, 1, 0) -
                  sparse_iteration_matrix(m, s, {0, 0, 0}, 1, 0);
  return d.topLeftCorner(m.nq(), m.nq());
}

/// K_t = ∂r/∂q (nq × nq, sparse) with the augmented-Lagrangian terms of the given k, ζ.
inline SpMat sparse_tangent_stiffness(const Model& m, const State& s, double k = 1,
                                      double zeta = 0) {
  return sparse_iteration_matrix(m, s, {0, 0, 1}, k, zeta).topLeftCorner(m.nq(), m.nq());
}

/// M = ∂r/∂q̈ (nq × nq): S(1, 0, 0) − S(0, 0, 0), exact because S is linear in (c_a, c_v, c_q).
inline Mat dense_mass_matrix(const Model& m, const State& s) {
  return (dense_iteration_matrix(m, s, {1, 0, 0}, 1, 0) -
          dense_iteration_matrix(m, s, {0, 0, 0}, 1, 0))
      .topLeftCorner(m.nq(), m.nq());
}

/// C_t = ∂r/∂q̇ (nq × nq).
inline Mat dense_damping_matrix(const Model& m, const State& s) {
  return (dense_iteration_matrix(m, s, {0, 1, 0}, 1, 0) -
          dense_iteration_matrix(m, s, {0, 0, 0}, 1, 0))
      .topLeftCorner(m.nq(), m.nq());
}

/// K_t = ∂r/∂q (nq × nq) with the augmented-Lagrangian terms of the given k, ζ.
inline Mat dense_tangent_stiffness(const Model& m, const State& s, double k = 1, double zeta = 0) {
  return dense_iteration_matrix(m, s, {0, 0, 1}, k, zeta).topLeftCorner(m.nq(), m.nq());
}

/// Relative difference ‖a − b‖∞ / max(‖b‖∞, floor).
inline double rel_diff(const Mat& a, const Mat& b, double floor = 1e-300) {
  return (a - b).lpNorm<Eigen::Infinity>() / std::max(b.lpNorm<Eigen::Infinity>(), floor);
}

}  // namespace lsmbs::test
