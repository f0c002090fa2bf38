#pragma once
// FlexibleBody — a plane-stress body meshed with cells of any registered element type
// (fem/element_types.hpp) whose nodes carry absolute positions. Element e has ρ_e = μ_e ρ0 and
// E_e = μ_e E0 (eq. 3), μ_e read from the body's material field in ModelParams::fields (1 by
// default; the geometry map sets it). The body holds its elements through the PlaneElement
// interface only.
#include <memory>
#include <string>
#include <vector>

#include "lsmbs/fem/mesh.hpp"
#include "lsmbs/fem/plane_element.hpp"
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
  ElementOptions element_options;  ///< how the elements are built (the case's "integration")
  /// Built from the mesh in the design frame (Model::add_flexible_body), one per cell.
  std::vector<std::unique_ptr<PlaneElement>> elements;
  int first_force = -1;  ///< index of element 0's PlaneForce in Model::forces()

  int node_dof(int node) const { return dof0 + 2 * node; }
  /// Node position at t = 0 (placed mesh).
  Vec2 placed(int node) const { return origin + rotation(angle) * mesh.nodes[node]; }
  /// Body-frame (mesh) coordinates of an inertial point at t = 0.
  Vec2 to_mesh_frame(const Vec2& x) const { return rotation(angle).transpose() * (x - origin); }
  double mass(const ModelParams& p) const;
  /// The 2n current coordinates of element e's nodes, gathered from q (interleaved x, y).
  int element_coordinates(int e, const Vec& q, double* x) const;
  /// The global DOF of coordinate k (0 … 2n−1) of element e.
  int element_dof(int e, int k) const { return node_dof(mesh.cells[e][k / 2]) + k % 2; }
};

/// One element of a flexible body as a ForceElement: consistent inertia, internal force, weight,
/// for any PlaneElement.
class PlaneForce : public ForceElement {
 public:
  PlaneForce(const FlexibleBody* body, int element);
  std::span<const int> dofs() const override { return {dofs_.data(), n_}; }
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override;
  bool uses_parameter(int j) const override {
    return j == body_->E_param || j == body_->nu_param || j == body_->rho_param ||
           j == body_->thickness_param;
  }
  /// Exact: r is linear in E0, ρ0 and t; ν enters through D
  /// (PlaneElement::internal_force_nu_derivative).
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;
  /// Constant consistent mass μ_e ρ0 t ∫ N_I N_J, no damping.
  void mass_damping(const LocalState& s, const ModelParams& p, LocalMat& M,
                    LocalMat& C) const override;
  /// The element reads μ_e of its body's material field.
  MaterialEntry material_entry() const override { return {body_->field, e_}; }
  /// ∂r/∂μ_e: r is linear in μ_e (ρ_e = μ_e ρ0, E_e = μ_e E0, eq. 3), so r_e / μ_e exactly.
  void field_derivative(const LocalState& s, const ModelParams& p, LocalVec& dr) const override;

 private:
  const FlexibleBody* body_;
  int e_;
  size_t n_ = 0;  // 2 × nodes
  std::array<int, kMaxLocalDofs> dofs_{};
};

}  // namespace lsmbs
