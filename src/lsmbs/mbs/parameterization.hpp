#pragma once
// Parameterization — a map p ↦ ModelParams from design variables to the model's parameters
// (material fields μ_e and named scalars). It is what a reference integrator needs to
// differentiate the model with respect to p on its own (IDAS forward sensitivities perturb p and
// re-evaluate the residual). The level-set design of the paper (design/design.hpp) is one.
#include <vector>

#include "lsmbs/mbs/model.hpp"

namespace lsmbs {

class Parameterization {
 public:
  virtual ~Parameterization() = default;
  virtual int size() const = 0;
  /// Lower and upper bounds of the variables (their range sets the scale of difference quotients).
  virtual Vec lower() const = 0;
  virtual Vec upper() const = 0;
  /// Writes the parameters at p into `params` (the entries p does not act on are left as they are).
  virtual void apply(const Vec& p, ModelParams& params) const = 0;
  /// apply() plus one direction ∂(ModelParams)/∂p_i per variable.
  virtual std::vector<ParamDirection> apply_with_directions(const Vec& p,
                                                            ModelParams& params) const = 0;
};

/// A parameterization restricted to directions: k variables s with p = p0 + W s (W: n × k) of a
/// base parameterization. Its sensitivities are the directional derivatives along W's columns:
/// an integrator differentiates along k directions instead of n variables (the IDAS reference of
/// `lsmbs verify` checks all variables at once along a few random combinations of them). The
/// variables' bounds are ±50, so that a difference quotient's scale max(|s|, 1e-2 range) is 1.
class DirectionalParameterization final : public Parameterization {
 public:
  DirectionalParameterization(const Parameterization& base, Vec p0, Mat W);
  int size() const override { return static_cast<int>(W_.cols()); }
  Vec lower() const override { return Vec::Constant(size(), -50.0); }
  Vec upper() const override { return Vec::Constant(size(), 50.0); }
  void apply(const Vec& s, ModelParams& params) const override;
  /// Direction j = Σ_i W_ij ∂(ModelParams)/∂p_i (entries of one material-field element merged).
  std::vector<ParamDirection> apply_with_directions(const Vec& s,
                                                    ModelParams& params) const override;

 private:
  const Parameterization& base_;
  Vec p0_;
  Mat W_;
};

}  // namespace lsmbs
