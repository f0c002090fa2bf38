#pragma once
// SolidBody — a 3D solid flexible body (fem/solid_element.hpp) whose nodes carry absolute
// positions, the spatial counterpart of FlexibleBody: element e has ρ_e = μ_e ρ0 and
// E_e = μ_e E0 (eq. 3), μ_e read from the body's material field (1 by default). Its nodes are
// tied to spatial rigid bodies and the ground by SolidNodeLink: a node at principal-frame offset
// d of a body in natural coordinates is x = r + Σ_k d_k e_k, linear in q (mbs/spatial.hpp), so
// a rigid connection is a linear constraint with a constant Jacobian.
#include <memory>
#include <string>
#include <vector>

#include "lsmbs/fem/hex_element.hpp"
#include "lsmbs/fem/solid_mesh.hpp"
#include "lsmbs/mbs/elements.hpp"

namespace lsmbs {

struct SolidBody {
  std::string name;
  SolidMesh mesh;  ///< node positions at t = 0 (ground frame)
  int dof0 = -1;
  int field = -1;  ///< index of μ in ModelParams::fields
  int E_param = -1, nu_param = -1, rho_param = -1;
  Vec3 gravity = Vec3::Zero();
  HexElement::Formulation formulation = HexElement::Formulation::kEnhanced;
  /// Built from the mesh (Model::add_solid_body), one per cell.
  std::vector<std::unique_ptr<SolidElement>> elements;
  int first_force = -1;  ///< index of element 0's SolidForce in Model::forces()

  int node_dof(int node) const { return dof0 + 3 * node; }
  double mass(const ModelParams& p) const;
  /// Element e's nodal coordinates gathered from q (3 per node, in the cell's order); returns
  /// their number.
  int element_coordinates(int e, const Vec& q, double* x) const;
  /// E_e = μ_e E0 and ν of element e (eq. 3).
  double element_E(int e, const ModelParams& p) const;
  double nu(const ModelParams& p) const { return p.scalars[static_cast<size_t>(nu_param)]; }
};

/// One element of a solid body as a ForceElement: consistent inertia, internal force, weight.
class SolidForce : public ForceElement {
 public:
  SolidForce(const SolidBody* body, int element);
  std::span<const int> dofs() const override { return {dofs_.data(), n_}; }
  /// r = μ ρ0 (M0 q̈ − N0 g) + f_int(μ E0, ν), M0 = ∫ N_I N_J dV, N0 = ∫ N_I dV.
  void evaluate(const LocalState& s, const ModelParams& p, LocalVec& r, const Coefficients* c,
                LocalMat* S) const override;
  std::string describe() const override;
  bool uses_parameter(int j) const override {
    return j == body_->E_param || j == body_->nu_param || j == body_->rho_param;
  }
  /// Exact: r is linear in E0 and ρ0; ν enters through C (SolidElement's ν derivative).
  void param_derivative(const LocalState& s, const ModelParams& p, int j,
                        LocalVec& dr) const override;
  void mass_damping(const LocalState& s, const ModelParams& p, LocalMat& M,
                    LocalMat& C) const override;
  MaterialEntry material_entry() const override { return {body_->field, e_}; }
  /// r is linear in μ_e: r_e / μ_e.
  void field_derivative(const LocalState& s, const ModelParams& p, LocalVec& dr) const override;

 private:
  const SolidBody* body_;
  int e_;
  size_t n_ = 0;  // 3 × nodes
  std::array<int, kMaxLocalDofs> dofs_{};
};

/// x_node − (r + Σ_k d_k e_k) = 0 for a node of a solid body and a spatial rigid body's point
/// (body_dof0 ≥ 0, d its principal-frame offset), or x_node − X = 0 for a ground point X
/// (body_dof0 < 0). Three linear equations.
class SolidNodeLink : public ConstraintElement {
 public:
  SolidNodeLink(int node_dof, int body_dof0, const Vec3& d_or_X);
  std::span<const int> dofs() const override { return {dofs_.data(), n_}; }
  int size() const override { return 3; }
  void evaluate(double t, const LocalVec& q, const ModelParams& p, LocalEqVec& phi,
                LocalJac* J) const override;
  void hessian(double t, const LocalVec& q, const LocalEqVec& w, LocalMat& H) const override;

 private:
  std::array<int, 15> dofs_{};
  size_t n_ = 0;
  bool ground_;
  Vec3 d_;
};

}  // namespace lsmbs
