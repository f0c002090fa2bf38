#pragma once
// One interface for the sensitivity methods of §4.3 (DESIGN.md): each method is a class behind
// SensitivityMethod; compute_sensitivities (sensitivity.hpp) picks one by
// SensitivityOptions::method.
//   DirectSensitivity          Algorithm 2: semi-analytical (forward or central Δp) and
//                              direct-analytic pseudo-loads, back-solves per step (eqs. 30–40)
//   FiniteDifferenceSensitivity  whole re-simulations per design variable (forward or central)
//   AdjointSensitivity         the discrete adjoint of the generalized-α solution: one backward
//                              pass of transposed solves for all responses
//   IdasSensitivity            SUNDIALS IDAS on the GGL form: forward sensitivities, or the
//                              adjoint of the time-integral responses
#include <memory>
#include <vector>

#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs {

class SensitivityMethod {
 public:
  explicit SensitivityMethod(SensitivityOptions o) : options_(std::move(o)) {}
  virtual ~SensitivityMethod() = default;
  const SensitivityOptions& options() const { return options_; }

  /// Sensitivities of the study's responses at design p (the study is not changed). Checks the
  /// study first (SetupError naming the missing part), measures the wall time, marks an
  /// interrupted run, and turns a NaN or an infinity in the results into a numerical failure.
  SensitivityResult compute(const Study& study, const Vec& p) const;

 protected:
  /// The method proper (called by compute), with `params`, the study's model parameters at p
  /// (parameters_at): the method's own, to perturb and restore as it needs.
  virtual SensitivityResult run(const Study& study, const Vec& p, ModelParams& params) const = 0;
  /// False when the grid responses carry no gradients (NaN by design), as with the IDAS adjoint.
  virtual bool grid_gradients() const { return true; }
  /// True when run() maps the design itself, with ∂μ/∂p (Design::apply_with_directions), before
  /// it reads `params`: compute() then hands it the model's parameters unmapped, instead of
  /// mapping the level sets twice (the mapping dominated the cost with many features).
  virtual bool maps_design() const { return false; }

 private:
  SensitivityOptions options_;
};

/// semi-analytical, semi-analytical-central, direct-analytic.
class DirectSensitivity final : public SensitivityMethod {
 public:
  using SensitivityMethod::SensitivityMethod;
  bool maps_design() const override { return true; }

 protected:
  SensitivityResult run(const Study& study, const Vec& p, ModelParams& params) const override;
};

/// adjoint: the discrete adjoint of generalized-α (adjoint_method.cpp).
class AdjointSensitivity final : public SensitivityMethod {
 public:
  using SensitivityMethod::SensitivityMethod;
  bool maps_design() const override { return true; }

 protected:
  SensitivityResult run(const Study& study, const Vec& p, ModelParams& params) const override;
};

/// fd-forward, fd-central.
class FiniteDifferenceSensitivity final : public SensitivityMethod {
 public:
  using SensitivityMethod::SensitivityMethod;

 protected:
  SensitivityResult run(const Study& study, const Vec& p, ModelParams& params) const override;
};

/// idas (forward sensitivities), idas-adjoint (time-integral responses).
class IdasSensitivity final : public SensitivityMethod {
 public:
  using SensitivityMethod::SensitivityMethod;
  /// Method idas on several output grids from one run, along the columns of `directions` when
  /// given (idas_on_grids, sensitivity.hpp): no checks, no timing.
  std::vector<SensitivityResult> run_on_grids(const Study& study, const Vec& p,
                                              const Mat* directions, double h_fine,
                                              const std::vector<int>& strides) const;

 protected:
  SensitivityResult run(const Study& study, const Vec& p, ModelParams& params) const override;
  bool grid_gradients() const override {
    return options().method != SensitivityOptions::Method::kIdasAdjoint;
  }
};

/// The method named by o.method.
std::unique_ptr<SensitivityMethod> make_sensitivity_method(const SensitivityOptions& o);

}  // namespace lsmbs
