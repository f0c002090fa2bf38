#pragma once
// Design — the design variables p of a case and what they act on: the level-set geometry of
// flexible bodies (one DesignMap per body; eq. 3: ρ_e = μ_e ρ0, E_e = μ_e E0 through the body's
// material field) and, through affine bindings, named scalar model parameters (a spring's
// stiffness, a mass, …). apply(p) writes both into ModelParams.
#include <memory>
#include <string>
#include <vector>

#include "lsmbs/geometry/design_map.hpp"
#include "lsmbs/mbs/model.hpp"
#include "lsmbs/mbs/parameterization.hpp"

namespace lsmbs {

struct DesignVariable {
  std::string name;
  double initial = 0, lower = 0, upper = 0;
};

struct BodyDesign {
  const FlexibleBody* body = nullptr;
  std::unique_ptr<DesignMap> map;
};

/// model parameter = offset + scale · p_variable
struct ParameterBinding {
  int parameter = -1;
  int variable = -1;
  double offset = 0, scale = 1;
};

class Design final : public Parameterization {
 public:
  std::vector<DesignVariable> variables;
  std::vector<BodyDesign> bodies;
  std::vector<ParameterBinding> bindings;

  int size() const override { return static_cast<int>(variables.size()); }
  Vec initial() const;
  Vec lower() const override;
  Vec upper() const override;
  int variable_index(const std::string& name) const;  ///< −1 if unknown

  /// Writes μ(p) into each designed body's field and bound parameter values into scalars.
  /// If dmu is given it receives ∂μ/∂p per designed body (same order as `bodies`).
  void apply(const Vec& p, ModelParams& params, std::vector<SpMat>* dmu) const;
  void apply(const Vec& p, ModelParams& params) const override { apply(p, params, nullptr); }
  /// apply() with ∂μ/∂p, returned as one parameter direction ∂(ModelParams)/∂p_i per variable
  /// (the mapping runs once).
  std::vector<ParamDirection> apply_with_directions(const Vec& p, ModelParams& params) const override;
  /// Mass of a designed body and its gradient m(p), ∂m/∂p = ρ t Σ_e A_e ∂μ_e/∂p.
  static double mass_gradient(const BodyDesign& b, const SpMat& dmu, const ModelParams& params, Vec& grad);
};

}  // namespace lsmbs
