#pragma once
// FlexibleBody — a plane-stress body meshed with 4-node quads whose nodes carry absolute
// positions. Element e has ρ_e = μ_e ρ0 and E_e = μ_e E0 (eq. 3), μ_e read from the body's
// material field in ModelParams::fields (1 by default; the geometry map sets it).
#include <string>
#include <vector>

#include "lsmbs/fem/mesh.hpp"
#include "lsmbs/fem/quad_element.hpp"
#include "lsmbs/mbs/elements.hpp"

namespace lsmbs {

struct FlexibleBody {
  std::string name;
  Mesh2D mesh;                 ///< in the body's own (design) frame
  Vec2 origin = Vec2::Zero();  ///< placement of the mesh frame at t = 0
  double angle = 0;
  int dof0 = -1;
  int field = -1;  ///< index of μ in ModelParams::fields
  int E_param = -1, nu_param = -1, rho_param = -1, thickness_param = -1;
  QuadIntegration integration = QuadIntegration::kSelectiveShear;
  std::vector<QuadElement> elements;  ///< built from the mesh in the design frame
  int first_force = -1;               ///< index of element 0's QuadForce in Model::forces()

  int node_dof(int node) const { return dof0 + 2 * node; }
  /// Node position at t = 0 (placed mesh).
  Vec2 placed(int node) const { return origin + rotation(angle) * mesh.nodes[node]; }
  /// Body-frame (mesh) coordinates of an inertial point at t = 0.
  Vec2 to_mesh_frame(const Vec2& x) const { return rotation(angle).transpose() * (x - origin); }
  double mass(const ModelParams& p) const;
};

/// One quad of a flexible body as a ForceElement: consistent inertia, internal force, weight.
class QuadForce : public ForceElement {
 public:
  QuadForce(const FlexibleBody* body, int element);
  std::span<const int> dofs() const override { return dofs_; }
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override;
  bool uses_parameter(int j) const override {
    return j == body_->E_param || j == body_->nu_param || j == body_->rho_param ||
           j == body_->thickness_param;
  }
  /// Exact: r is linear in E0, ρ0 and t; ν enters through D
  /// (QuadElement::internal_force_nu_derivative).
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;
  /// Constant consistent mass μ_e ρ0 t ∫ N_I N_J, no damping.
  void mass_damping(const LocalState& s, const ModelParams& p, LocalMat& M,
                    LocalMat& C) const override;

 private:
  const FlexibleBody* body_;
  int e_;
  std::array<int, 8> dofs_;
};

}  // namespace lsmbs
