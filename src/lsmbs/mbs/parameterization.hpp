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

}  // namespace lsmbs
