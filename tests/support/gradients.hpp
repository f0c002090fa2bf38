#pragma once
// Gradient comparisons of the sensitivity tests: one run of a method, and the error metric.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "lsmbs/sensitivity/sensitivity.hpp"
#include "support/test_models.hpp"

namespace lsmbs::test {

/// How a gradient error is normalized.
enum class Norm {
  /// per response value (each step of a per-step response on its own): ‖g − g_ref‖∞ over the
  /// variables / ‖g_ref‖∞ of that value
  kPerValue,
  /// per response: max over values and variables of |g − g_ref| / max |g_ref| of the response
  /// (steps whose gradient is small by cancellation carry no relative accuracy in any method)
  kPerResponse,
};

/// Largest gradient error over all responses; `where` receives the response (and value index).
inline double worst_relative(const SensitivityResult& a, const SensitivityResult& ref, Norm norm = Norm::kPerValue,
                             std::string* where = nullptr) {
  double worst = 0;
  EXPECT_EQ(a.responses.size(), ref.responses.size());
  for (size_t r = 0; r < ref.responses.size() && r < a.responses.size(); ++r) {
    const Mat& A = a.responses[r].gradient;
    const Mat& B = ref.responses[r].gradient;
    EXPECT_EQ(A.rows(), B.rows());
    EXPECT_EQ(A.cols(), B.cols());
    if (A.rows() != B.rows() || A.cols() != B.cols()) continue;
    if (norm == Norm::kPerResponse) {
      const double n = B.cwiseAbs().maxCoeff();
      if (n == 0) continue;
      const double e = (A - B).cwiseAbs().maxCoeff() / n;
      if (e > worst) {
        worst = e;
        if (where) *where = ref.responses[r].name;
      }
      continue;
    }
    for (Eigen::Index i = 0; i < B.rows(); ++i) {
      const double n = B.row(i).cwiseAbs().maxCoeff();
      if (n == 0) continue;
      const double e = (A.row(i) - B.row(i)).cwiseAbs().maxCoeff() / n;
      if (e > worst) {
        worst = e;
        if (where) *where = ref.responses[r].name + "[" + std::to_string(i) + "]";
      }
    }
  }
  return worst;
}

/// Sensitivities of the case at its initial design (expects success).
inline SensitivityResult gradients(Case& cs, SensitivityOptions::Method method,
                                   SensitivityOptions::Matrix matrix = SensitivityOptions{}.matrix,
                                   double delta = 1e-6, bool relative = true) {
  SensitivityOptions o;
  o.method = method;
  o.matrix = matrix;
  o.delta = delta;
  o.relative = relative;
  auto r = compute_sensitivities(cs, cs.design->initial(), o);
  EXPECT_TRUE(r.ok) << r.message;
  return r;
}

/// The shipped rigid slider-crank with a spring–damper whose stiffness k and damping c are the
/// design variables.
inline nlohmann::json spring_crank_json() {
  return nlohmann::json::parse(
      std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/slider_crank_rigid/slider_crank_spring.json"));
}

}  // namespace lsmbs::test
