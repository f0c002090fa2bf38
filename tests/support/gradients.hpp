#pragma once
// Gradient comparisons of the sensitivity tests: one run of a method, and the error metric.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"
#include "support/test_models.hpp"

namespace lsmbs::test {

using Norm = GradientNorm;

/// Largest gradient error over all responses (compare_gradients, expecting the same shapes);
/// `where` receives the response (and value index).
inline double worst_relative(const SensitivityResult& a, const SensitivityResult& ref,
                             Norm norm = Norm::kPerValue, std::string* where = nullptr) {
  EXPECT_EQ(a.responses.size(), ref.responses.size());
  for (size_t r = 0; r < ref.responses.size() && r < a.responses.size(); ++r) {
    EXPECT_EQ(a.responses[r].gradient.rows(), ref.responses[r].gradient.rows());
    EXPECT_EQ(a.responses[r].gradient.cols(), ref.responses[r].gradient.cols());
  }
  const GradientDifference d = compare_gradients(a.responses, ref.responses, norm);
  if (where) *where = d.where;
  return d.worst;
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
  return nlohmann::json::parse(std::ifstream(std::string(LSMBS_SOURCE_DIR) +
                                             "/data/slider_crank_rigid/slider_crank_spring.json"));
}

}  // namespace lsmbs::test
