#pragma once
// Four-node plane-stress quadrilateral, total Lagrangian, St Venant–Kirchhoff material, in
// absolute nodal coordinates (Géradin & Cardona): the unknowns are the current positions x_I
// of the nodes, X_I their reference positions.
//   F = Σ x_I ⊗ ∇_X N_I,  E = ½(FᵀF − I),  S = D E (plane stress),
//   W = t ∫ ½ E:D:E dA,   f_int = ∂W/∂x,  K = ∂f_int/∂x (material + geometric).
// Two integration variants:
//  * kFull: 2×2 Gauss for everything (locks in bending on coarse meshes),
//  * kSelectiveShear (default): normal strains with 2×2 Gauss, the shear term G (2E₁₂)² with
//    one point. The split is exact for isotropic D (no normal–shear coupling), keeps objectivity
//    (E is invariant under rigid rotation) and passes the patch test; it removes parasitic
//    shear in bending (see docs/methods.md and the cantilever test).
// Consistent mass M_IJ = ρ t ∫ N_I N_J dA (2×2 Gauss, exact: det J of a bilinear quad is linear).
#include <array>
#include <memory>
#include <vector>

#include "lsmbs/core/types.hpp"
#include "lsmbs/fem/cell.hpp"
#include "lsmbs/fem/plane_element.hpp"

namespace lsmbs {

enum class QuadIntegration { kFull, kSelectiveShear };

struct QuadMaterial {
  double E = 0, nu = 0, rho = 0, thickness = 0;
};

class QuadElement final : public PlaneElement {
 public:
  using Vec8 = Eigen::Matrix<double, 8, 1>;
  using Mat8 = Eigen::Matrix<double, 8, 8>;
  using Mat4 = Eigen::Matrix<double, 4, 4>;

  QuadElement() = default;
  /// X: reference node positions, counter-clockwise. Throws if the element is inverted.
  QuadElement(const std::array<Vec2, 4>& X, QuadIntegration integration);

  /// Internal force of unit-E material scaled by `scale_E` (E_e = μ_e E0, eq. 3).
  /// x: current positions (x1,y1,...,x4,y4). K may be null.
  void internal_force(const Vec8& x, double E, double nu, double thickness, Vec8& f, Mat8* K) const;
  /// ∂f_int/∂ν: f_int = t Σ w Bᵀ D(E, ν) E_GL is linear in D, so this is the same sum with
  /// ∂D/∂ν (exact; f_int is linear in E and t, which need no separate function).
  void internal_force_nu_derivative(const Vec8& x, double E, double nu, double thickness,
                                    Vec8& df) const;
  double strain_energy(const Vec8& x, double E, double nu, double thickness) const;
  /// ∫ N_I N_J dA (multiply by ρ t for the consistent mass of one direction).
  const Mat4& unit_mass4() const { return unit_mass_; }
  /// ∫ N_I dA (for body loads and lumped quantities).
  const Eigen::Vector4d& shape_integrals4() const { return shape_int_; }
  double area() const override { return area_; }
  /// Green–Lagrange strain (E11, E22, 2E12) and deformation gradient at the centre.
  void centre_strain(const Vec8& x, Eigen::Vector3d& E_voigt, Mat2& F) const;
  /// The smallest det F over the integration points (2×2 Gauss and the centre). det F ≤ 0 is an
  /// inverted element: E = ½(FᵀF − I) does not see a reflection, so a reflected element is
  /// stress-free and a spurious solution of the equations of motion.
  double min_det_F(const Vec8& x) const;
  /// The smallest det F at the element's corners (where the reference quad is convex): ≤ 0 with a
  /// positive min_det_F is a folded (bow-tie) element, a state the integration points do not see.
  double min_corner_det_F(const Vec8& x) const;
  /// ∇_X N_I at the element centre (rows I), for stresses evaluated there.
  Eigen::Ref<const Eigen::MatrixX2d> centre_gradients() const override { return centre_G_; }

  // ---- PlaneElement: the functions above on interleaved coordinates
  int num_nodes() const override { return 4; }
  void internal_force(const double* x, double E, double nu, double t, double* f,
                      double* K) const override;
  void internal_force_nu_derivative(const double* x, double E, double nu, double t,
                                    double* df) const override;
  double strain_energy(const double* x, double E, double nu, double t) const override;
  Eigen::Ref<const Eigen::MatrixXd> unit_mass() const override { return unit_mass_dyn_; }
  Eigen::Ref<const Eigen::VectorXd> shape_integrals() const override { return shape_int_dyn_; }
  void centre_strain(const double* x, Eigen::Vector3d& E, Mat2& F) const override;
  double min_det_F(const double* x) const override;
  double min_corner_det_F(const double* x) const override;

 private:
  struct Point {
    Eigen::Matrix<double, 4, 2> G;  // ∇_X N_I
    double w = 0;                   // weight × det J
  };
  std::array<Point, 4> gauss_{};
  std::array<double, 4> corner_det_J_{};  // det ∂X/∂ξ at the corners (≤ 0: not checked)
  Point centre_{};
  QuadIntegration integration_ = QuadIntegration::kSelectiveShear;
  Mat4 unit_mass_ = Mat4::Zero();
  Eigen::Vector4d shape_int_ = Eigen::Vector4d::Zero();
  double area_ = 0;
  // the same, in the interface's dynamic types
  Eigen::MatrixXd unit_mass_dyn_;
  Eigen::VectorXd shape_int_dyn_;
  Eigen::MatrixX2d centre_G_;
};

/// The bilinear quadrilateral's shape: sub-cells of the parent square (midpoint rule), marching
/// squares for contours (a saddle decided by the mean of the four nodal values).
class QuadShape final : public CellShape {
 public:
  int num_nodes() const override { return 4; }
  double area(const Vec2* X) const override;
  double min_det_J(const Vec2* X) const override;
  void samples(const Vec2* X, int n, std::vector<CellSample>& out) const override;
  void contour(const Vec2* X, const double* phi,
               std::vector<std::pair<Vec2, Vec2>>& out) const override;
};

}  // namespace lsmbs
