#pragma once
// Observed order of convergence: errors e_0, e_1, … at step sizes divided by `ratio` each time
// give the orders log(e_i / e_{i+1}) / log(ratio).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

namespace lsmbs::test {

inline std::vector<double> observed_orders(const std::vector<double>& errors, double ratio = 2) {
  std::vector<double> p;
  for (size_t i = 0; i + 1 < errors.size(); ++i)
    p.push_back(std::log(errors[i] / errors[i + 1]) / std::log(ratio));
  return p;
}

/// Expects every observed order within expected ± tol; prints the errors and orders.
inline void expect_order(const std::vector<double>& errors, double expected, double tol,
                         const char* what, double ratio = 2) {
  const auto p = observed_orders(errors, ratio);
  std::printf("%s: errors", what);
  for (double e : errors) std::printf(" %.3e", e);
  std::printf("; orders");
  for (double o : p) std::printf(" %.3f", o);
  std::printf("\n");
  for (size_t i = 0; i < p.size(); ++i)
    EXPECT_NEAR(p[i], expected, tol) << what << ": refinement " << i + 1;
}

}  // namespace lsmbs::test
