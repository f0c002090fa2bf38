#pragma once
// Built-in gradient check, in the spirit of Ceres' GradientChecker: the directional derivative
// of every response along one random unit direction d (in variables scaled by
// s_i = max(|p_i|, 1e-2 (upper_i − lower_i))), by central differences of two re-simulations at
// p ± δ (s ∘ d), against the method's gradient projected on the same direction, ∇r · (s ∘ d).
// Two simulations whatever the number of variables; a wrong gradient passes only if its error is
// orthogonal to a random direction.
#include <functional>
#include <string>
#include <vector>

#include "lsmbs/core/status.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs {

struct GradientCheckOptions {
  /// Relative step δ along the scaled direction. 1e-4 balances the central difference's
  /// truncation error (δ²) against the simulations' own noise (a Newton-converged response
  /// carries ~1e-12 of relative noise): at 1e-5 the shipped coarse rod's max_elongation, a
  /// response that moves 1e-9 of itself over the step, disagreed by 1.2e-3 from noise alone (the
  /// error fell as 1/δ: 8.0e-5 at 1e-4, 1.7e-5 at 1e-3; docs/case-format.md).
  double delta = 1e-4;
  unsigned seed = 20261122;  ///< seed of the random direction (recorded; same seed, same direction)
  double warn = 1e-3;        ///< relative disagreement above which the check warns
  double fail = 5e-2;        ///< … and above which `optimize` refuses to start
  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
};

struct GradientCheckResult {
  struct Entry {
    std::string response;
    double finite_difference = 0;  ///< largest |D_k| over the response's values
    double method = 0;             ///< largest |∇r_k · (s ∘ d)|
    double relative_error =
        0;  ///< max_k |D_k − ∇r_k·(s∘d)| / max(|D_k|, |∇r_k·(s∘d)|, 1e-3 ‖∇r_k ∘ s‖₂)
  };
  Vec direction;  ///< unit direction d (scaled variables)
  Vec step;       ///< the variable step δ (s ∘ d)
  std::vector<Entry> entries;
  double worst = 0;
  std::string worst_response;
  long simulations = 0;
  bool ok = true;            ///< both simulations succeeded
  bool interrupted = false;  ///< stopped by SIGINT/SIGTERM (core/interrupt.hpp): no verdict
  std::string message;
  /// "pass", "warn" or "fail"; "interrupted" when the check did not finish
  std::string verdict(const GradientCheckOptions& o) const;
  RunStatus status() const;
  std::string report() const;  ///< outcome, and per response the two directional derivatives
};

/// How compare_gradients normalizes a gradient difference.
enum class GradientNorm {
  /// per response value (each step of a per-step response on its own):
  /// ‖g − g_ref‖∞ over the variables / ‖g_ref‖∞ of that value
  kPerValue,
  /// per response: max over values and variables of |g − g_ref| / max |g_ref| of the response.
  /// A step where a per-step response is still at rest has gradients at round-off level, and
  /// relative errors there say nothing.
  kPerResponse,
};

struct GradientDifference {
  double worst = 0;   ///< largest normalized difference (+inf when the shapes differ)
  std::string where;  ///< the response (and "[value index]" with kPerValue) where it is
};

/// Largest normalized difference between two methods' gradients of the same responses (in the
/// same order); references that are exactly zero are skipped.
GradientDifference compare_gradients(const std::vector<ResponseSensitivity>& a,
                                     const std::vector<ResponseSensitivity>& reference,
                                     GradientNorm norm = GradientNorm::kPerValue);

/// Checks `gradients` (as computed by compute_sensitivities at p) along one random direction.
/// Responses without gradients (NaN, e.g. idas-adjoint's grid aggregates) are skipped.
GradientCheckResult check_gradients(const Study& cs, const Vec& p,
                                    const std::vector<ResponseSensitivity>& gradients,
                                    const GradientCheckOptions& o = {});
/// The same check with the responses at the perturbed designs from `simulate(p, counts)` (plain
/// runs, values only), for responses that are not one study's (service conditions). A
/// NumericalFailure of `simulate` makes the check fail, saying why.
using ResponseSimulator =
    std::function<std::vector<ResponseSensitivity>(const Vec& p, SensitivityCounts& counts)>;
GradientCheckResult check_gradients(const Design& d, const Vec& p,
                                    const std::vector<ResponseSensitivity>& gradients,
                                    const GradientCheckOptions& o,
                                    const ResponseSimulator& simulate);

}  // namespace lsmbs
