#pragma once
// Three-node plane-stress triangle (constant strain), total Lagrangian, St Venant–Kirchhoff, in
// absolute nodal coordinates — the element of Gmsh's triangle meshes. Linear shape functions have
// constant gradients, so one integration point (the centroid, weight A) integrates the strain
// energy exactly. It is stiff in bending (a plate needs several elements through its depth); the
// element exists for meshes of real parts that Gmsh triangulates, and it proves that a body, the
// level-set map, the pictures and the outputs take any element registered in
// fem/element_types.cpp.
//   Consistent mass ∫ N_I N_J dA = A/12 (1 + δ_IJ),  ∫ N_I dA = A/3.
#include <array>
#include <vector>

#include "lsmbs/fem/cell.hpp"
#include "lsmbs/fem/plane_element.hpp"

namespace lsmbs {

class TriElement final : public PlaneElement {
 public:
  /// X: reference node positions, counter-clockwise. Throws lsmbs::Error if inverted.
  explicit TriElement(const std::array<Vec2, 3>& X);
  int num_nodes() const override { return 3; }
  void internal_force(const double* x, double E, double nu, double t, double* f,
                      double* K) const override;
  void internal_force_nu_derivative(const double* x, double E, double nu, double t,
                                    double* df) const override;
  double strain_energy(const double* x, double E, double nu, double t) const override;
  Eigen::Ref<const Eigen::MatrixXd> unit_mass() const override { return unit_mass_; }
  Eigen::Ref<const Eigen::VectorXd> shape_integrals() const override { return shape_int_; }
  double area() const override { return area_; }
  void centre_strain(const double* x, Eigen::Vector3d& E, Mat2& F) const override;
  Eigen::Ref<const Eigen::MatrixX2d> centre_gradients() const override { return G_dyn_; }
  double min_det_F(const double* x) const override;
  double min_corner_det_F(const double* x) const override { return min_det_F(x); }

 private:
  Eigen::Matrix<double, 3, 2> G_;  // ∇_X N_I, constant
  Eigen::MatrixX2d G_dyn_;
  Eigen::MatrixXd unit_mass_;
  Eigen::VectorXd shape_int_;
  double area_ = 0;
};

/// The linear triangle's shape: n² similar sub-triangles (midpoint rule at their centroids),
/// marching triangles for contours (exact for a linear field).
class TriShape final : public CellShape {
 public:
  int num_nodes() const override { return 3; }
  double area(const Vec2* X) const override;
  double min_det_J(const Vec2* X) const override { return 2 * area(X); }
  void samples(const Vec2* X, int n, std::vector<CellSample>& out) const override;
  void contour(const Vec2* X, const double* phi,
               std::vector<std::pair<Vec2, Vec2>>& out) const override;
};

}  // namespace lsmbs
