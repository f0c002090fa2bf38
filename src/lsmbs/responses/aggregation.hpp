#pragma once
// Aggregation of one measure column f_n over the grid steps of a time window into a response,
// with its gradient from the total derivatives df_n/dp (eq. 24) — one implementation for the
// simulate path (values only) and the sensitivity and optimize paths (values and gradients).
//
//   average       (1/n) Σ f_n                      (eq. 45 with the number of summed steps)
//   average_eq45  (1/(n − 1)) Σ f_n                (eq. 45 as printed: n_cvf − n_cvi)
//   integral      trapezoidal rule over the window's steps
//   rms           sqrt((1/n) Σ f_n²)
//   max, min      the extreme step's value and derivative (not differentiable where it switches)
//   final         the last step of the window
//   ks            (1/ks) ln Σ exp(ks f_n), a smooth upper bound of the maximum, evaluated as
//                 m + (1/ks) ln Σ exp(ks (f_n − m)), m = max f_n
//   per_step      one value per step of the window (the local formulation, eq. 42)
// n is the number of grid steps in the window (both ends included).
#include <limits>
#include <string>
#include <vector>

#include "lsmbs/core/types.hpp"

namespace lsmbs {

struct ResponseSpec {
  enum class Kind { kAverage, kAverageEq45, kMax, kMin, kFinal, kIntegral, kRms, kPerStep, kKS };
  std::string name;
  int column = 0;  ///< column in the history (0 = first measure component)
  Kind kind = Kind::kAverage;
  double t0 = -1e300, t1 = 1e300;
  double ks = 0;            ///< KS parameter [1/unit of the measure]
  std::string window_text;  ///< how the window was given, for the summary
  static const char* kind_name(Kind k);
  /// Unit of a response of this kind over a measure of unit `measure_unit`: the measure's, or
  /// for an integral the measure's times seconds ("m" → "m*s", "m/s" → "m").
  static std::string unit(Kind k, const std::string& measure_unit);
};

/// A response aggregated over its window.
struct Aggregate {
  std::vector<double> values;  ///< one value; per_step: one per step of the window
  std::vector<double> times;   ///< per_step: the step time of each value (empty otherwise)
  Mat gradient;                ///< values.size() × n_v (n_v = 0 when no derivatives were given)
  int count = 0;               ///< grid steps in the window
  /// Scalar kinds: ∂(value)/∂f_n for every step n of the input (zero outside the window), so
  /// that the gradient is Σ_n w_n df_n/dp (the adjoint's source terms); per_step: empty.
  std::vector<double> weights;
  /// max and min: the time of the step whose value is taken (NaN for the other kinds). Where it
  /// moves to another step between two designs the response has a kink there.
  double extreme_time = std::numeric_limits<double>::quiet_NaN();
  /// The response as one number: the value, or the largest per-step value (NaN: empty window or
  /// average_eq45 of one step).
  double scalar() const;
};

/// Aggregates the per-step values v_n at the grid times t_n (steps within [t0, t1] up to 1e-9 of
/// the first step). G (row n: df_n/dp, one column per design variable) is optional; without it
/// the gradient has no columns.
Aggregate aggregate(const ResponseSpec& r, const std::vector<double>& t,
                    const std::vector<double>& v, const Mat* G = nullptr);

}  // namespace lsmbs
