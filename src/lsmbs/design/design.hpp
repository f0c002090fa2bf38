#pragma once
// Design — the design variables p of a case and what they act on: the level-set geometry of
// flexible bodies (one DesignMap per body; eq. 3: ρ_e = μ_e ρ0, E_e = μ_e E0 through the body's
// material field) and, through affine bindings, named scalar model parameters (a spring's
// stiffness, a mass, …). apply(p) writes both into ModelParams.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lsmbs/geometry/design_map.hpp"
#include "lsmbs/geometry/solid_design_map.hpp"
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
  /// Features [0, num_design_features) of the level set are design features, the others
  /// non-design regions (GeometrySpec::non_design).
  int num_design_features = 0;
};

/// The level-set geometry of one flexible body (docs/case-format.md, "design"): design features
/// (holes, or solids), non-design features (solid inside, OR-ed with the region: material kept
/// there whatever the design does), and the region that combines the design features.
struct GeometrySpec {
  std::vector<Feature> features;    ///< the design features
  std::vector<Feature> non_design;  ///< solid inside, OR-ed with the region
  /// The Boolean combination of `features` (leaves index into it); none: material where every
  /// design feature is positive (the paper's intersection of holes, eq. 4).
  std::optional<LevelSetNode> region;
  MappingOptions options;
};

/// The 3D level-set geometry of one solid body (docs/case-format.md, "Designs of solid bodies").
struct SolidBodyDesign {
  const SolidBody* body = nullptr;
  std::unique_ptr<SolidDesignMap> map;
  int num_design_features = 0;
};

/// A solid body's geometry as a case gives it: as GeometrySpec, with 3D features.
struct SolidGeometrySpec {
  std::vector<Feature3> features;
  std::vector<Feature3> non_design;
  std::optional<LevelSetNode> region;
  MappingOptions options;
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
  std::vector<SolidBodyDesign> solid_bodies;
  std::vector<ParameterBinding> bindings;

  // ---------------------------------------------------------- building a design in code
  /// Adds a variable lower < upper with lower ≤ initial ≤ upper and returns its index
  /// (SetupError "design.variables" otherwise, or for a name in use).
  int add_variable(const std::string& name, double initial, double lower, double upper);
  /// The feature parameter `offset + scale · p_variable` (Table 2's linked parameters).
  ParamBinding variable(const std::string& name, double scale = 1, double offset = 0) const;
  /// A constant feature parameter.
  static ParamBinding constant(double value) { return ParamBinding{value, 0, -1}; }
  /// Level-set features on a flexible body: material where every feature is positive (the
  /// paper's intersection of holes, eq. 4), mapped to μ_e on the body's mesh.
  void add_geometry(const FlexibleBody& body, std::vector<Feature> features, MappingOptions o = {});
  /// A body's geometry as a case file gives it. Refused (SetupError "design.geometry", naming the
  /// feature as its entity): a body with two geometries; a feature degenerate somewhere within
  /// the design bounds (its parameters are affine in the variables: checked at the bounds); a
  /// feature wholly outside its body that no design variable moves, or that no values within the
  /// bounds bring in. Add the variables first.
  void add_geometry(const FlexibleBody& body, GeometrySpec spec);
  /// A solid body's 3D geometry. Refused (SetupError "design.geometry", naming the feature): a
  /// body with two geometries, a feature degenerate within the design bounds, a feature wholly
  /// outside the body that no design variable moves.
  void add_geometry(const SolidBody& body, SolidGeometrySpec spec);
  /// model parameter `parameter` (Model::parameter_index) = offset + scale · p_variable.
  /// Refused (SetupError "design.parameters"): an unknown variable or parameter, a parameter bound
  /// twice, or one that leaves its admissible range (ModelBuilder::check_parameter_value) at a
  /// bound of the variable (it is affine in it). `name` is the parameter's name, for the check and
  /// the messages.
  void bind(int parameter, const std::string& variable, double scale = 1, double offset = 0,
            const std::string& name = "");

  int size() const override { return static_cast<int>(variables.size()); }
  Vec initial() const;
  Vec lower() const override;
  Vec upper() const override;
  int variable_index(const std::string& name) const;  ///< −1 if unknown
  /// How far outside a bound a value may lie and still be that bound, relative to the range
  /// upper − lower: a value computed as lower + 1.0·(upper − lower), or an optimizer's step onto a
  /// bound (SciPy's SLSQP), lands there by round-off.
  static constexpr double kBoundTolerance = 1e-10;
  /// `v` for variable i, snapped onto a bound it lies within kBoundTolerance·(upper − lower) of
  /// (inside or outside); any other value is returned as given (the callers refuse those outside).
  double snap_to_bounds(int i, double v) const;

  /// Writes μ(p) into each designed body's field and bound parameter values into scalars.
  /// If dmu is given it receives ∂μ/∂p per designed body (`bodies`, then `solid_bodies`).
  void apply(const Vec& p, ModelParams& params, std::vector<SpMat>* dmu) const;
  void apply(const Vec& p, ModelParams& params) const override { apply(p, params, nullptr); }
  /// apply() with ∂μ/∂p, returned as one parameter direction ∂(ModelParams)/∂p_i per variable
  /// (the mapping runs once).
  std::vector<ParamDirection> apply_with_directions(const Vec& p,
                                                    ModelParams& params) const override;
  /// Empty, or a warning that two level-set features coincide at p within the smoothing bands
  /// of an exact (ks = 0) Boolean combination: at such a design point μ(p) has a kink and every
  /// gradient is one-sided (checked at the mesh nodes within 12 bands of the boundary, where the
  /// two features' distances agree also one band away in x and in y).
  std::string coincident_features(const Vec& p) const;
  /// Empty, or a warning that level-set features lie wholly outside their body at p
  /// (DesignMap::features_outside_mesh): they have no effect there until a design variable
  /// moves them in.
  std::string features_outside(const Vec& p) const;
  /// Empty if every design variable drives something, else a warning naming those that no
  /// feature parameter (with a nonzero scale) and no model parameter is bound to: their gradient
  /// is zero whatever the design, and an optimizer leaves them where they start.
  std::string idle_variables() const;
  /// Mass of a designed body and its gradient m(p), ∂m/∂p = ρ t Σ_e A_e ∂μ_e/∂p.
  static double mass_gradient(const BodyDesign& b, const SpMat& dmu, const ModelParams& params,
                              Vec& grad);
};

}  // namespace lsmbs
